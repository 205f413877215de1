// canhil/external/external_run.hpp — the owner of a run with the team's own
// processes (`canhil run --external`, each half of `canhil match
// --external`, `canhil bench --part external`): built from a session whose
// plan carries the resolved [external] settings (emulator::ExternalPlan), it
// holds the lockstep conductor, the external driver, the team's processes
// and, alone on the user-space bus, the broker's spin; it starts the
// processes (or says how to start them by hand), waits for them to attach,
// drives, reaps, and stops them.
//
//   RunPlan ─> Session ─> ExternalRun{Conductor, ExternalDriver, TeamProcesses} ─> run_until ... stop
//
// Not thread-safe: the thread that drives the session owns it.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "canhil/base/time.hpp"
#include "canhil/emulator/external_driver.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/external/team_processes.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "canhil/userbus/bus.hpp"

namespace canhil::external {

/// Exit status of a run whose process stopped answering, or never attached.
inline constexpr int kProcessStuckStatus = 3;

/// How a run starts and watches its processes; the limits come from the plan.
struct ExternalSetup {
  std::string shim;          ///< the time shim (find_timeshim)
  std::string team_preload;  ///< what the team's processes keep preloaded after it
  FILE* say = stdout;        ///< starts, ends, how to start processes by hand
  ProcessOutput output;      ///< the processes' own output
  /// Alone on its bus: the broker may look for frames before it sleeps
  /// (spin_the_bus). Not for runs side by side, which would take each
  /// other's cores.
  bool spin_bus = true;
  /// With no command lines: how many processes started by hand to wait for
  /// (0: two per robot, a handler and an agent).
  std::size_t wait_for = 0;
  bool record_trace = true;   ///< ExternalOptions::record_trace
  bool check_timing = false;  ///< ExternalOptions::check_timing
  /// What the run is called in a ProcessStuck's text ("match 1, half 2"), or nothing.
  std::string name;
};

class ExternalRun {
 public:
  /// The conductor, the driver (its sockets opened now) and the broker's spin;
  /// nothing started yet. SetupError as ExternalDriver's.
  ExternalRun(emulator::Session& session, ExternalSetup setup);
  ~ExternalRun();  ///< stop()
  ExternalRun(const ExternalRun&) = delete;
  ExternalRun& operator=(const ExternalRun&) = delete;

  /// Starts the plan's launches, or, where it has none, says on `say` how to
  /// start processes by hand and waits for wait_for of them; returns once
  /// all have attached. emulator::ProcessStuck ("N of M process(es) attached
  /// within S s ...") when they do not within the plan's attach limit;
  /// SetupError when a process's log cannot be written.
  void start();
  /// Drives the session to `end` (virtual time) and reaps what ended.
  /// emulator::ProcessStuck ("at t = T s: ...") when a process stopped
  /// answering, or ended without running its program.
  void run_until(Nanos end);
  /// Ends the processes' waits (they take their SIGINT) and stops them. Once.
  void stop();

  Nanos now() const { return driver_.now(); }
  emulator::ExternalDriver& driver() noexcept { return driver_; }
  const emulator::ExternalDriver& driver() const noexcept { return driver_; }
  const lockstep::Conductor& conductor() const noexcept { return conductor_; }
  /// The team's processes: how those that ended, ended.
  const TeamProcesses& processes() const noexcept { return processes_; }
  const std::string& name() const noexcept { return setup_.name; }
  /// How many processes it waits for (after start()).
  std::size_t expected() const noexcept { return expected_; }

 private:
  // `what`, after the run's name and `joint` when it has one.
  std::string named(const char* joint, const std::string& what) const;

  emulator::Session& session_;
  ExternalSetup setup_;
  lockstep::Conductor conductor_;
  emulator::ExternalDriver driver_;
  TeamProcesses processes_;
  std::unique_ptr<userbus::BrokerSpin> spin_;
  std::size_t expected_ = 0;
  bool stopped_ = false;
};

}  // namespace canhil::external
