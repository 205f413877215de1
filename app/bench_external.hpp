// app/bench_external.hpp — `canhil bench --part external`: the one-robot
// real-time factor with canhil's reference handler and agent as processes in
// lockstep (canhil run --external), next to the same scenario in-process, in
// one run and on one core; and where the external run's wall time went.
#pragma once

#include <memory>
#include <string>

#include "canhil/frames/messages.hpp"

namespace canhil::app {

struct ExternalBench {
  std::string iface = "vcan0";
  double seconds = 20;  ///< virtual time of each run
  int cpu = 0;          ///< the core both runs and the processes are pinned to; -1: not pinned
  std::string shim;     ///< find_timeshim()
  std::string team_preload;
};

/// Prints the figures; true when the external run reaches at least 20x real time.
bool bench_external(const ExternalBench& bench, const std::shared_ptr<const frames::MessageSet>& messages);

}  // namespace canhil::app
