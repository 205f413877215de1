// canhil/emulator/world_log.hpp — the world log (`canhil run --virtual-time
// --world-log FILE`), written and read here only: the session writes it, the
// replay (`canhil view FILE`) and the tests read it.
//
// CSV: a header, then one row every period of the run's clock (from 0), with
// the ball and, per robot, its true pose and the pose its handler reports in
// the RTDB (zeros while it reports none). Lines starting with '#' are what
// CSV readers take as comments: with two teams, who played for whom before
// the first row; with a referee, its calls among the rows in time order
// (TEAM "-" for a dropped ball, then the score per team). Two teams of one
// robot each, a row and a call:
//
//   time_s,ball_x_m,ball_y_m,ball_z_m,robot0_x_m,robot0_y_m,robot0_heading_deg,robot0_reported_x_m,...
//   #team,0,home,+x
//   #team,1,away,-x
//   #robot,0,0,1,vcan0
//   #robot,1,1,1,vcan1
//   0.000,0.0000,0.0000,0.1100,-1.0000,0.0000,0.00,0.0000,0.0000,0.00,1.0000,0.0000,180.00,0.0000,0.0000,0.00
//   #referee,12.340,throwin,away,3.000,6.000,0,0
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/kinematics/omni.hpp"

namespace canhil::emulator {

/// A "#team,INDEX,NAME,+x|-x" line.
struct WorldLogTeam {
  std::string name;
  bool attacks_positive_x = true;
};

/// A "#robot,INDEX,TEAM,AGENT,INTERFACE" line (a log without one: team 0,
/// agent index + 1, interface "robot INDEX").
struct WorldLogRobot {
  std::size_t team = 0;
  int agent = 0;
  std::string interface;
};

/// A "#referee,TIME,RESTART,TEAM,SPOT_X,SPOT_Y,SCORE..." line.
struct WorldLogCall {
  double time_s = 0;
  std::string restart;  ///< restart_name()'s words: "throwin", "kickoff", ...
  std::string team;     ///< the taker's name, "-" for none
  double spot_x_m = 0, spot_y_m = 0;
  std::vector<std::string> score;  ///< goals per team, as written
};

class WorldLogWriter {
 public:
  /// The header for `robots` robots; with more than one team, the "#team"
  /// and "#robot" lines. `period` above 0.
  WorldLogWriter(Nanos period, const std::vector<WorldLogTeam>& teams, const std::vector<WorldLogRobot>& robots);

  /// Whether a row is due at `now` (then begin_row moves the next one on).
  bool due(Nanos now) const noexcept { return now >= next_; }
  /// A row: begin_row, robot() for every robot in order, end_row.
  void begin_row(Nanos now, const Eigen::Vector3d& ball);
  void robot(const kinematics::Pose& pose, const kinematics::Pose& reported);
  void end_row() { text_ += '\n'; }
  /// A referee's call among the rows.
  void call(const WorldLogCall& call);

  const std::string& text() const noexcept { return text_; }

 private:
  Nanos period_;
  Nanos next_{0};
  std::string text_;
};

/// A world log as read back.
struct WorldLog {
  std::vector<std::string> columns;
  std::size_t robots = 0;
  std::vector<std::vector<double>> rows;  ///< in time order, columns.size() values each
  std::vector<WorldLogTeam> teams;        ///< empty when the log does not say (one team's never do)
  std::vector<WorldLogRobot> robot_info;  ///< one per robot
  std::vector<WorldLogCall> calls;
};

/// Reads a world log; SetupError naming the file and line of what does not
/// read (a header that is not a world log's, a row of the wrong width, a
/// value that is not a number, time going back, no rows). A '#' line that
/// does not read as a team, robot or call is a comment like any other.
WorldLog read_world_log(const std::filesystem::path& path);

}  // namespace canhil::emulator
