// app/run_external.hpp — `canhil run --external`: a session in virtual time
// with the team's own handler and agent as processes in lockstep
// (emulator::ExternalDriver, docs/lockstep.md). canhil preloads the time shim
// into itself (it starts itself again once, with LD_PRELOAD), starts the
// scenario's [external] processes per robot (or waits for processes started
// by hand), runs, and reports the real-time factor and how the wall time
// split between canhil and each process.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "canhil/emulator/session.hpp"
#include "canhil/lockstep/conductor.hpp"

namespace canhil::app {

struct ExternalRun {
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

/// Exit status 3: a process stopped answering (named on stderr); the trace
/// and the world log are still written.
inline constexpr int kProcessStuckStatus = 3;

/// The time shim's path: $CANHIL_TIMESHIM, next to an installed canhil, or
/// the build tree's. SetupError naming the places looked at.
std::string find_timeshim();

/// Makes sure canhil's own clocks can follow the lockstep board: when the shim
/// is not preloaded yet, starts canhil again (same arguments) with it; the
/// process then goes on with the team's LD_PRELOAD restored for what it
/// starts. Returns the preload the team's processes should keep after the shim
/// (LD_PRELOAD as canhil was first given it). SetupError when it cannot.
std::string preload_shim_into_self(const std::string& shim);

/// Runs the session; returns the exit status (0, 130 after Ctrl-C, kProcessStuckStatus).
int run_external(emulator::Session& session, const ExternalRun& run, const std::string& shim,
                 const std::string& team_preload, ExternalFigures* figures = nullptr);

}  // namespace canhil::app
