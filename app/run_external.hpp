// app/run_external.hpp — `canhil run --external`: a session in virtual time
// with the team's own handler and agent as processes in lockstep
// (external::ExternalRun, docs/lockstep.md), run and reported: the real-time
// factor and how the wall time split between canhil and each process.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "canhil/emulator/session.hpp"
#include "canhil/lockstep/conductor.hpp"

namespace canhil::app {

struct ExternalRequest {
  emulator::RunLength length{20, "the default"};
  bool quiet = false;
  std::optional<std::string> trace, world_log;
  double log_period_s = 0.05;
  std::size_t wait_for = 0;  ///< processes started by hand to wait for (0: two per robot)
};

/// What a run measured: `canhil bench --part external` reads it.
struct ExternalFigures {
  Nanos simulated{0};  ///< virtual time reached
  Nanos wall{0};       ///< from the processes' start to the run's end
  Nanos waited{0};     ///< of `wall`, canhil waiting for the processes
  std::vector<lockstep::ProcessReport> processes;
  std::uint64_t looks_answered = 0;  ///< canhil's looks before sleeping that something ended (spin_us)
  std::uint64_t sleeps = 0;          ///< and those that ended in a sleep
};

/// Runs the session (canhil already under the time shim: external::preload_shim_into_self);
/// returns the exit status (0, 130 after Ctrl-C, external::kProcessStuckStatus).
int run_external(emulator::Session& session, const ExternalRequest& run, const std::string& shim,
                 const std::string& team_preload, ExternalFigures* figures = nullptr);

}  // namespace canhil::app
