// canhil/emulator/scenario.hpp — what a run is: the world (every table of
// physics/config/world.toml: field, ball, robot model, [[robots]] with their
// start poses, [[obstacles]], ball_start) plus a [run] table:
//
//   [run]
//   duration_s = 20                  # how long a run lasts (default 20 s in virtual time;
//                                    #   in real time: until Ctrl-C when not given)
//   seed = 1                         # fault draws
//   kick_power = 40                  # the reference agent's kick, 0..max_power
//   interfaces = ["vcan0"]           # one per robot; default vcan0, vcan1, ...
//   agents = [1]                     # one per robot, 1..6; default 1, 2, ...
//   faults = ["drop:M4_1:0.1"]       # see can_nodes/fault.hpp
//   emulate = ["Motor1", "Motor2"]   # nodes canhil emulates (default all); the others
//                                    #   are real boards on the bus (real time only);
//                                    #   or one list per robot; [[teams.robots]] emulate
//
//   [coach]                          # the base station's orders (emulator/coach.hpp)
//   game_state = "start"             # stop, start, our_kickoff, ...
//   running = [true]                 # one per robot
//   roles = ["striker"]              # one per robot, role names of the team's layout
//
//   [laptop]                         # the team's laptop software (docs/own-software.md)
//   rtdb_lib = "builtin"             # or the team's librtdb.so (its simulator API)
//   rtdb_items = "rtdb_user.h"       # the team's generated item ids, and
//   rtdb_ini = "rtdb.ini"            #   its item table, for a team library
//   layout = "canhil"                # "cambada", "canhil" or a layout file (docs/layouts.md)
//   pman = "builtin"                 # "builtin", "none" or the team's libpman.so
//   pman_processes = ["agent"]       # registered per robot as NAME<agent>
//   coach_period_s = 0.1             # COACH_INFO written again this often
//   relocation_delay_s = 0.1         # a moved robot's COACH_INFO relocations count this much later
//   replicate = true                 # the wireless: shared items copied between agents
//   replicate_period_s = 0.1
//
//   [vision]                         # the camera's imperfections (default: exact)
//   point_noise_m = 0.02             #   Gaussian sigma on line and obstacle points
//   ball_noise_m = 0.05              #   on the ball
//   detection_probability = 0.95     #   of each point and ball
//   latency_s = 0.0                  #   what a frame shows is this old
//   [bus]                            # the robots' CAN buses (docs/wire.md)
//   bit_rate = 1000000               #   the wire's bit/s (default: the DBC's Baudrate);
//                                    #   0: instant, as vcan (no wire time, no errors)
//   data_bit_rate = 0                #   CAN FD's data phase (0: the bit rate)
//   restart_ms = 100                 #   a bus-off controller restarts after (0: only on request)
//   tx_queue = 10                    #   frames a controller queues (can-dev's txqueuelen)
//   [firmware]                       # the emulated nodes' firmware, where a team's differs
//   watchdog_ms = 150                #   Pic_base brakes after this long without an M6
//   motor_watchdog_ms = 100          #   a motor node brakes after this long without an M1
//   alive_timeout_ms = 200           #   the system monitor calls a node dead after this long unseen
//   [referee]                        # goals, kick-offs, throw-ins, corners, dropped balls
//   enabled = true                   #   (default: with two teams); each rule can be off:
//   kickoff_after_goal = true        #   out_of_play, dropped_ball; stuck_s = 10,
//   restart_pause_s = 2              #   stuck_radius_m = 0.5, touch_distance_m = 0.05,
//   in_play_distance_m = 0.5         #   restart_distance_m = 1; the restart taken: in play
//
//   [[teams]]                        # two teams on one computer (docs/teams.md); instead
//   name = "new"                     #   of [[robots]], run.interfaces/agents and the
//   attacks = "+x"                   #   coach's per-robot lists
//   game_state = "start"             # this team's coach state (default [coach].game_state)
//   [teams.laptop]                   # its own laptop side (default: [laptop])
//   [teams.external]                 # its own processes (default: [external])
//   [[teams.robots]]                 # x_m, y_m, heading_deg, interface, agent,
//   x_m = -2.0                       #   running, role, role_auto
//
// Paths are relative to the scenario file. A physics world file (no [run]) is a scenario too. The defaults are filled
// in, and the rules checked, in one place (complete()), for files and for
// scenarios built in code alike. Mistakes in a file are physics::ConfigError:
// `FILE:LINE: run.FIELD: what; what to do`. The shipped scenarios are in
// emulator/scenarios/.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/can_nodes/node_ids.hpp"
#include "canhil/emulator/coach.hpp"
#include "canhil/emulator/referee.hpp"
#include "canhil/physics/params.hpp"

namespace canhil::emulator {

/// Agent numbers a robot may have: CAMBADA_1 .. CAMBADA_6 of the RTDB configuration.
inline constexpr int kFirstAgent = 1;
inline constexpr int kLastAgent = 6;

/// Where the one robot of a world without robots stands: 3 m behind the
/// centre spot, facing the opponent goal (+x).
inline constexpr physics::Placement kDefaultPlacement{-3.0, 0.0, -90.0};

/// LaptopSide::relocation_delay_s's default: a vision frame (33 ms) and a
/// compass message (M8, every 50 ms) after the move, with room to spare.
inline constexpr double kRelocationDelayS = 0.1;

/// The team's laptop side: which RTDB and PMan libraries canhil writes
/// through, and in which layout. Empty: the command line's or the defaults.
struct LaptopSide {
  std::string rtdb_lib;    ///< "builtin" (canhil's, linked in) or a path to the team's library
  std::string rtdb_items;  ///< the team's rtdb_user.h (item ids), with a team library
  std::string rtdb_ini;    ///< the team's rtdb.ini (item sizes and owners), with a team library
  std::string layout;      ///< "canhil", "cambada" or a layout description file
  std::string pman;        ///< "builtin", "none" or a path to the team's libpman.so
  std::vector<std::string> pman_processes = {"agent"};  ///< registered per robot as NAME<agent>
  double coach_period_s = 0.1;  ///< COACH_INFO / FORMATION_INFO written again this often (and at changes)
  /// A robot canhil moves (the referee's placements, the viewer, a control
  /// command) counts one relocation in COACH_INFO this long after the move
  /// (CoachPlayer::relocations). At least one vision frame and one compass
  /// message (M8, 50 ms) must come between: an agent that relocalises at
  /// once uses what it saw before the move (CAMBADA's did, bumped in the
  /// move's own cycle; 67 ms and 0.33 s later it found itself).
  double relocation_delay_s = kRelocationDelayS;
  std::optional<bool> replicate;    ///< copy shared items between agents (default: with more than one robot)
  double replicate_period_s = 0.1;  ///< the replicator's cycle
};

/// The team's own processes in a virtual-time run (`canhil run --external`,
/// docs/lockstep.md): started per robot by canhil under the time shim, with
/// AGENT set, `{agent}` and `{iface}` replaced by the robot's agent number and
/// interface. None: canhil prints what to set and waits for them to be
/// started by hand.
struct ExternalSide {
  std::vector<std::string> processes;  ///< shell command lines, one process each, per robot
  double answer_limit_s = 1.0;         ///< wall time a process may take over one instant
  double attach_limit_s = 60.0;        ///< wall time the processes may take to start, until they first all wait
  double busy_limit_s = 60.0;          ///< wall time an instant may take while the processes compute on the CPU
  /// How long canhil looks for the processes' answer before it sleeps
  /// (lockstep::ConductorOptions::spin); 0: at once.
  double spin_us = 50;
  /// On canhil's user-space bus, run alone: how long its broker keeps looking
  /// for the next frame before it sleeps (userbus::BrokerSpin); 0: at once.
  double bus_spin_us = 200;
  /// Where the processes' syslog(3) messages go: "log", each process's own
  /// standard error (its log with --logs), one line a message as LOG_PERROR
  /// writes it; "system", the machine's syslog, as without canhil.
  std::string syslog = "log";
};

/// Robots that play together: one goal to attack, one RTDB set (the first
/// team's agents are spaces 1..6 of the first set, the second team's of the
/// second: both use agent numbers 1..6), one coach. A scenario without
/// [[teams]] is one team attacking +x, named "canhil".
struct Team {
  std::string name;
  bool attacks_positive_x = true;  ///< the goal it scores in: at +x (length/2) or at -x
  std::size_t first_robot = 0;     ///< its robots are world.robots[first_robot .. first_robot + robots)
  std::size_t robots = 0;
  std::optional<LaptopSide> laptop;      ///< its own laptop side; none: the scenario's [laptop]
  std::optional<ExternalSide> external;  ///< its own processes; none: the scenario's [external]
};

/// The emulated camera's imperfections ([vision]); each given one replaces
/// SessionOptions::vision's (exact geometry by default). Each robot's camera
/// draws from the run's seed.
struct VisionImperfections {
  std::optional<double> point_noise_m;          ///< Gaussian sigma on line and obstacle points
  std::optional<double> ball_noise_m;           ///< Gaussian sigma on the ball
  std::optional<double> detection_probability;  ///< of each ball, line and obstacle point
  std::optional<double> latency_s;              ///< what a frame shows is this old
  bool any_noise() const noexcept {
    return point_noise_m.value_or(0) > 0 || ball_noise_m.value_or(0) > 0 || detection_probability.value_or(1) < 1;
  }
};

/// The robots' CAN buses ([bus]): what the file says, resolved with the
/// command line and the message set into BusPhysics by plan_run().
struct BusSettings {
  std::optional<std::uint32_t> bit_rate;  ///< 0: instant
  std::optional<std::uint32_t> data_bit_rate;
  std::optional<double> restart_ms;  ///< 0: on request only
  std::optional<std::size_t> tx_queue;
};

/// The emulated nodes' firmware settings ([firmware]); unset: the defaults
/// of can_nodes::NodeParams (docs/nodes.md).
struct FirmwareSettings {
  std::optional<double> watchdog_ms;
  std::optional<double> motor_watchdog_ms;
  std::optional<double> alive_timeout_ms;
};

/// At most two teams (CAMBADA's RTDB has two sets of databases).
inline constexpr std::size_t kMostTeams = 2;

/// How long a run lasts and who said so (the first line of a run prints both).
struct RunLength {
  double seconds = 0;  ///< 0: until Ctrl-C (real time only)
  std::string source;  ///< "--duration", "the scenario's duration_s", ...
};

struct Scenario {
  physics::WorldParams world;
  double duration_s = 20;
  bool duration_given = false;  ///< [run] duration_s was in the file (it then holds in real time too)
  std::uint64_t seed = 1;
  int kick_power = 40;
  std::vector<std::string> interfaces;  ///< one per robot after complete()
  std::vector<int> agents;              ///< one per robot after complete()
  std::vector<can_nodes::FaultRule> faults;
  /// Per robot, the nodes canhil emulates (the rest are real boards on its
  /// bus); after complete() one per robot, all eight where not given.
  std::vector<can_nodes::NodeSet> emulate;
  CoachState coach;  ///< one player per robot after complete()
  LaptopSide laptop;
  ExternalSide external;
  std::string source_toml;     ///< the text it was parsed from (empty: built in code)
  std::vector<Team> teams;     ///< one or two after complete(), covering every robot in order
  RefereeRules referee;        ///< [referee]; on by default with two teams
  VisionImperfections vision;  ///< [vision]
  BusSettings bus;             ///< [bus]
  FirmwareSettings firmware;   ///< [firmware]

  std::size_t robot_count() const noexcept { return world.robots.size(); }
  /// True when some robot leaves a node to a real board (after complete()).
  bool mixes_real_boards() const noexcept;
  /// The team robot r plays in (after complete()).
  std::size_t team_of(std::size_t robot) const noexcept;
  /// A team's laptop side and processes: its own, else the scenario's.
  const LaptopSide& laptop_of(std::size_t team) const noexcept;
  const ExternalSide& external_of(std::size_t team) const noexcept;
  /// The run's length: `flag` (--duration) over the scenario's duration_s
  /// over the default; in real time the default is until Ctrl-C, and a flag
  /// of 0 asks for that whatever the scenario says. Throws SetupError for a
  /// length that is not a number of seconds above 0 (0 too in virtual time).
  RunLength run_length(std::optional<double> flag, bool realtime) const;
};

/// Fills in what the scenario leaves out — one robot at kDefaultPlacement when
/// it places none, interfaces vcan0, vcan1, ... and agents 1, 2, ... per
/// team, one team "canhil" attacking +x when it names none — and checks the
/// rest: at most two teams, each of at most kLastAgent robots, one interface
/// and one agent each, interfaces all different, agents in range and
/// different within a team. Throws SetupError saying what to change.
/// Idempotent.
void complete(Scenario& scenario);

/// Parses and completes a scenario (or a physics world file).
Scenario parse_scenario(std::string_view toml_text, const std::string& file_name);
Scenario load_scenario(const std::filesystem::path& path);
/// The file's values, not completed: plan_run() completes it once, after the
/// command's overrides. SetupError naming the file, line and field.
Scenario read_scenario(const std::filesystem::path& path);

/// The scenario installed with canhil (share/canhil/scenarios/NAME), or the
/// one in the source tree.
std::filesystem::path shipped_scenario(const std::string& name);

}  // namespace canhil::emulator
