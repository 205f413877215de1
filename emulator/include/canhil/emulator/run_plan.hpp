// canhil/emulator/run_plan.hpp — a run resolved once, before anything starts:
// the scenario with every default filled in (complete()), every override of
// the command line applied, every team's laptop side resolved, the run's
// length and where it came from. A Session is built from a plan and never
// changes it; what a run prints first and the world log's header come from
// it. (The model/data split of physics engines, applied to a whole run: the
// plan is the model, the Session the data.)
//
//   scenario file ──┐
//   command line ───┴─ plan_run() ─> RunPlan (const) ─> Session ─> a driver
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/node_ids.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session_options.hpp"
#include "canhil/lockstep/conductor.hpp"

namespace canhil::emulator {

/// How a run moves through time.
enum class RunMode : std::uint8_t {
  kVirtual,   ///< virtual time, everything in one process (VirtualDriver)
  kRealtime,  ///< the wall clock, on SocketCAN beside the team's processes (RealtimeDriver)
  kExternal,  ///< virtual time with the team's processes in lockstep (ExternalDriver)
};

/// What a command line, or a command itself, may say over a scenario; unset:
/// the scenario's value, else canhil's default. Applied in plan resolution
/// only: nothing changes a loaded Scenario but plan_run().
struct RunOverrides {
  RunMode mode = RunMode::kVirtual;
  // The first team's laptop side ([laptop]).
  std::optional<std::string> rtdb_lib, rtdb_items, rtdb_ini, layout;
  std::optional<std::string> pman;  ///< a library path, "builtin" or "none"
  std::optional<std::uint64_t> seed;
  std::optional<int> kick_power;
  std::optional<double> duration_s;      ///< 0: until stopped (real time only)
  std::vector<std::string> faults;       ///< more fault rules, as `--fault` takes them
  std::vector<std::string> processes;    ///< [external] processes (every team's that gives none)
  std::optional<double> answer_limit_s;  ///< every team's [external] answer limit
  std::optional<double> bit_rate;        ///< the buses' wire (--bit-rate): 0 instant, else 10000..1000000 bit/s
  // What commands say beyond their command lines:
  std::optional<int> half;                  ///< a match's half (0-based): odd halves change ends (half_scenario)
  std::optional<std::size_t> robots;        ///< only the first N robots (`canhil nodes`: one)
  std::vector<std::string> interfaces;      ///< the robots' interfaces, robot by robot (empty: the scenario's)
  std::vector<int> agents;                  ///< the robots' agent numbers, robot by robot (empty: the scenario's)
  std::vector<can_nodes::NodeSet> emulate;  ///< the nodes canhil emulates, robot by robot (empty: the scenario's)
};

/// A value of the command line that cannot be used: what() names the option
/// and what it takes (the command reports it as a usage error).
class OverrideError : public SetupError {
 public:
  using SetupError::SetupError;
};

/// One of the team's processes as a run with them starts it: a command line
/// of its team's [teams.external] (else [external]) for one robot, its
/// placeholders filled in (expand_command).
struct Launch {
  std::size_t robot = 0;
  std::size_t team = 0;
  int agent = 0;        ///< AGENT
  std::string command;  ///< the shell command line, expanded
  std::string syslog;   ///< where its syslog(3) messages go (ExternalSide::syslog)
};

/// A run with the team's processes (RunMode::kExternal), resolved from every
/// team's [teams.external], else the scenario's [external].
struct ExternalPlan {
  /// Every process waits on the one virtual clock, so each limit is the
  /// longest any team gives (answer_limit_s, busy_limit_s, spin_us): a team's
  /// processes get at least their own team's.
  lockstep::ConductorOptions conductor;
  double attach_limit_s = 0;  ///< the longest attach_limit_s of the teams
  double bus_spin_us = 0;     ///< the longest bus_spin_us of the teams
  /// Every robot's processes, robot by robot; none: the user starts them.
  std::vector<Launch> launches;
  /// Where processes the user starts send their syslog messages (the scenario's [external]).
  std::string syslog;
};

struct RunPlan {
  std::filesystem::path source;     ///< the scenario file as given; empty for a scenario built in code
  Scenario scenario;                ///< complete, the overrides applied, laptops resolved (with vision)
  std::vector<LaptopSide> laptops;  ///< per team, as its LaptopLink opens it (none without vision)
  SessionOptions options;
  RunLength length;
  ExternalPlan external;  ///< with options.external; empty otherwise
  /// The mode, as the options say it (external, real time, else virtual).
  RunMode mode() const noexcept {
    return options.external ? RunMode::kExternal : options.realtime ? RunMode::kRealtime : RunMode::kVirtual;
  }
};

/// The plan of a scenario in hand (built in code, or loaded by a command
/// that says more over it: matches, benchmarks, `canhil nodes`): `overrides`
/// applied (their mode aside: options.realtime and options.external say it),
/// complete(), with vision every team's laptop resolved (the defaults of a
/// real-time run when options.realtime or options.external) and the
/// scenario's [vision] imperfections merged into options.vision, the run's
/// length, with options.external the [external] settings. SetupError saying
/// what to change; OverrideError for an override that cannot be used.
RunPlan plan_run(Scenario scenario, SessionOptions options, const RunOverrides& overrides = {});

/// A run's buses in a line (what plan_run chose and who chose it), for its
/// first lines: "each robot's bus on a timed wire at 1000 kbit/s (the DBC's
/// Baudrate; --bit-rate 0: instant)" or the instant bus and how to time it.
std::string describe_bus(const BusPhysics& bus);

/// The scenario of half `half` (0-based) of a match (RunOverrides::half): in
/// odd halves the teams change ends (every robot's place turned about the
/// centre spot, each team attacking the other goal) and swap their starting
/// game states (the other team kicks off).
Scenario half_scenario(const Scenario& scenario, int half);

/// `scenario` with `overrides` applied (their mode and duration aside), not
/// yet complete: for a command that checks what a run would start before it
/// plans one (`canhil match --external`: the processes, the goals they are
/// told). OverrideError as plan_run's.
Scenario overridden(Scenario scenario, const RunOverrides& overrides);

/// A command line with robot `robot`'s values in place of "{agent}",
/// "{iface}", "{x}", "{y}", "{heading}" (its start placement: metres,
/// degrees) and "{goal_x}" (the x of the goal its team attacks, metres),
/// numbers as "%g" prints them. `scenario`: complete().
std::string expand_command(std::string command, const Scenario& scenario, std::size_t robot);

/// The plan of a scenario file (nullopt: the shipped one-robot scenario) and
/// a command line's overrides; options.realtime and options.external follow
/// the mode. SetupError naming the file, line and field for the scenario;
/// OverrideError for an override that cannot be used.
RunPlan plan_run(const std::optional<std::filesystem::path>& file, const RunOverrides& overrides,
                 SessionOptions options);

}  // namespace canhil::emulator
