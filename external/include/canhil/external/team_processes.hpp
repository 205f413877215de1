// canhil/external/team_processes.hpp — the team's own processes for a session
// in virtual time: the plan's launches (emulator::ExternalPlan, per robot each
// command line of its team's [teams.external], else [external]) started with
// the lockstep's environment, AGENT, SECOND_RTDB for the second team and
// canhil's laptop programs on the PATH; reaped as they end; stopped with
// SIGINT, then SIGKILL, when the session is over. ExternalRun owns them.
//
// Not thread-safe: the thread that drives the session owns it.
#pragma once

#include <sys/types.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "canhil/userbus/bus.hpp"

namespace canhil::external {

/// While it lives, the broker of canhil's user-space bus, when the session's
/// robots are on it, looks for each next frame for the longest bus_spin_us of
/// the teams' sides before it sleeps (userbus::BrokerSpin). Nothing on the
/// kernel's SocketCAN, or when that is 0. For a run alone: lockstep runs side
/// by side (`match --jobs 2`) each have a bus of their own, and spinning
/// brokers would take each other's cores.
std::unique_ptr<userbus::BrokerSpin> spin_the_bus(const emulator::Session& session);

/// Every team that attacks the -x goal (in any half, with `both_ends`: a
/// match of more than one half changes ends) must be told so: its layout
/// carries COACH_INFO's `attacks` (CAMBADA's goalColor), or one of the command
/// lines canhil starts for it passes "{goal_x}". Software told nothing
/// believes it attacks +x and plays backwards: SetupError naming the team and
/// both ways. A team whose processes the user starts (no command lines) gets
/// a warning on `warn` instead: canhil cannot see what they are told.
void require_told_goal(const emulator::Scenario& scenario, bool both_ends, FILE* warn);

/// Where the processes' own output goes: one file per process under `folder`
/// (PREFIX TEAM-agentN-PROGRAM.log), else canhil's stdout and stderr, or both
/// into its stderr (`onto_stderr`: a match's stdout may be JSON).
struct ProcessOutput {
  std::optional<std::string> folder;
  std::string prefix;
  bool onto_stderr = false;
};

/// How one of the team's processes ended.
struct ProcessEnd {
  std::string command;
  int agent = 0;
  pid_t pid = -1;
  bool signalled = false;  ///< ended by a signal (code: its number), else by exit (code: its status)
  int code = 0;
  /// The virtual time it was found ended while the run went on; none when
  /// the run's end stopped it (stop_all).
  std::optional<Nanos> during_run;
};

class TeamProcesses {
 public:
  /// `environment`: the lockstep's (Conductor::environment), NAME=VALUE each.
  /// `say`: where starts and ends are reported (stdout for a run, stderr for
  /// a match, whose stdout may be JSON).
  TeamProcesses(std::vector<std::string> environment, FILE* say, ProcessOutput output = {});
  ~TeamProcesses();  ///< stop_all()
  TeamProcesses(const TeamProcesses&) = delete;
  TeamProcesses& operator=(const TeamProcesses&) = delete;

  /// Starts the session's plan's launches; returns how many. SetupError when
  /// a log file cannot be opened.
  std::size_t start_all(const emulator::Session& session);
  /// Reaps what ended; says so once per process, with the virtual time `now`.
  void reap(Nanos now);
  /// Why a process that has ended never ran its program, for the first such:
  /// the shell's exit status 127 (not found) or 126 (not executable). Empty
  /// when none: a program that ran and ended is the team's to mind, as a
  /// crash on the robot would be.
  std::string not_started() const;
  /// SIGINT (their Ctrl-C), then SIGKILL for any still there after five seconds.
  void stop_all();
  std::size_t started() const noexcept { return started_.size(); }
  /// The processes that have ended so far, in the order they were started.
  std::vector<ProcessEnd> ends() const;
  /// What every process is started with (NAME=VALUE each).
  const std::vector<std::string>& environment() const noexcept { return environment_; }

 private:
  struct Started {
    std::string command;
    int agent = 0;
    pid_t pid = -1;
    int status = 0;
    bool ended = false;
    std::optional<Nanos> ended_at;  // found ended by reap(), while the run went on
  };
  std::vector<std::string> environment_;
  FILE* say_;
  ProcessOutput output_;
  std::vector<Started> started_;
};

}  // namespace canhil::external
