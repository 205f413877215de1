// canhil/verdict/test_file.hpp — a team's regression test as a file: a
// scenario, events at times (the faults and coach orders canhil already
// knows, a ball moved, a set-pose), and named expectations on the bus, the
// world and the team's RTDB, each with its verdict after the run (`canhil
// test`, docs/testing-your-software.md):
//
//   [test]
//   name = "brake on silence"          # default: the file's name
//   scenario = "../one_robot.toml"     # relative to this file
//   duration_s = 4                     # default: the scenario's
//   seed = 1                           # default: the scenario's
//   bit_rate = 1000000                 # default: the scenario's ([bus], else the DBC's)
//   faults = ["drop:M4_1:0.1"]         # more rules from the start
//   external = true                    # the scenario's [external] processes (the team's
//                                      #   handler and agent) in lockstep, as with --external
//
//   [[events]]
//   name = "laptop silent"             # what expectations call it (default: "event N")
//   at_s = 1.0
//   fault = "silence:laptop:1"         # or coach = "stop" (robot = N, running = false: one
//                                      #   robot's), ball = [x, y] or [x, y, vx, vy],
//                                      #   set_pose = [x_m, y_m, heading_rad] (robot = N)
//   [[expect]]
//   name = "the robot brakes"
//   speed_below_m_s = 0.05             # one check per expectation: see Check
//   after = "laptop silent"
//   within_ms = 500
//
// Every mistake is a physics::ConfigError naming the file, the line and the
// field, and what to write instead.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/kinematics/omni.hpp"

namespace canhil::verdict {

/// What happens at a time in a test's run.
struct Event {
  enum class Kind : std::uint8_t { kFault, kCoach, kBall, kSetPose };
  std::string name;  ///< "event N" (1-based) unless the file names it
  double at_s = 0;
  int line = 0;
  Kind kind = Kind::kFault;
  can_nodes::FaultRule fault;             ///< kFault: from at_s on (its own @SECONDS added)
  std::optional<std::string> game_state;  ///< kCoach: every team's
  std::optional<bool> running;            ///< kCoach: robot's
  std::size_t robot = 0;                  ///< kCoach with running, kSetPose
  double ball[4] = {0, 0, 0, 0};          ///< kBall: x, y, vx, vy
  kinematics::Pose pose;                  ///< kSetPose
};

/// What an expectation checks (its one key in the file).
enum class Check : std::uint8_t {
  kBallInGoal,      ///< ball_in_goal = "opponent" | "own" | "+x" | "-x" | "any", by_s
  kRobotNear,       ///< robot_near = "ball" | [x, y], within_m, by_s (from_s)
  kSpeedBelow,      ///< speed_below_m_s, after = EVENT (or after_s), within_ms, hold_ms
  kFttViolations,   ///< ftt_violations_at_most (message = NAME: only its)
  kErrorFrames,     ///< error_frames_at_most
  kJitter,          ///< jitter_p99_at_most_ms, message = NAME
  kHandlerLatency,  ///< handler_latency_p99_at_most_ms (the reference handler's)
  kWithinBounds,    ///< within_bounds = true: `canhil timing --analyse` schedulable, the trace inside every bound
  kRtdb,            ///< rtdb = "ITEM.quantity", between = [lo, hi], at_s or from_s, age_at_most_ms
  kProcesses,       ///< processes_ok = true (--external): all attached, none stuck or ended early; exit_codes
};
/// The check's key as a file writes it.
const char* check_key(Check c) noexcept;

struct Expectation {
  std::string name;
  int line = 0;
  Check check = Check::kBallInGoal;
  std::size_t robot = 0;  ///< whose bus, pose or database
  // the world
  std::string goal;               ///< kBallInGoal
  bool near_ball = false;         ///< kRobotNear: the ball, else point
  double point[2] = {0, 0};       ///< kRobotNear
  double within_m = 0.5;          ///< kRobotNear
  double from_s = 0;              ///< kRobotNear, kRtdb: from then on
  std::optional<double> by_s;     ///< kBallInGoal, kRobotNear (default: the end)
  double speed_m_s = 0;           ///< kSpeedBelow
  std::string after;              ///< kSpeedBelow: an event's name
  std::optional<double> after_s;  ///< kSpeedBelow: or a time
  double within_ms = 500;         ///< kSpeedBelow
  double hold_ms = 200;           ///< kSpeedBelow: it stays below this long
  // the bus
  std::uint64_t at_most = 0;  ///< kFttViolations, kErrorFrames
  std::string message;        ///< kFttViolations (optional), kJitter
  double bound_ms = 0;        ///< kJitter, kHandlerLatency
  // the RTDB
  std::string item, quantity;    ///< kRtdb
  double low = 0, high = 0;      ///< kRtdb: between
  std::optional<double> at_s;    ///< kRtdb: at this instant (else from from_s to the end)
  std::optional<double> age_ms;  ///< kRtdb: at most this old
  // the team's processes
  std::vector<int> exit_codes;  ///< kProcesses: the statuses allowed when the run's end stops them (empty: any)
};

struct TestFile {
  std::filesystem::path path;  ///< as given
  std::string name;
  std::filesystem::path scenario;  ///< resolved against the file's folder
  std::optional<double> duration_s;
  std::optional<std::uint64_t> seed;
  std::optional<double> bit_rate;
  std::vector<std::string> faults;
  bool external = false;      ///< with the scenario's [external] processes
  std::vector<Event> events;  ///< in time order (a stable sort of the file's)
  std::vector<Expectation> expectations;
  /// The event named `name`, or nullptr.
  const Event* event(const std::string& name) const;
};

/// Reads and checks a test file (not its scenario: the run loads that);
/// physics::ConfigError for a mistake, SetupError for a file that cannot be read.
TestFile load_test_file(const std::filesystem::path& path);
/// The same from text (`file_name` for messages and relative paths).
TestFile parse_test_file(const std::string& text, const std::filesystem::path& file_name);

}  // namespace canhil::verdict
