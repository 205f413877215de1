#include "canhil/emulator/world_log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>

#include "canhil/base/located_error.hpp"

namespace canhil::emulator {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    out.push_back(line.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

// A mistake at line `line` of the log.
[[noreturn]] void refuse(const std::filesystem::path& file, std::size_t line, const std::string& what) {
  throw LocatedError(file.string(), static_cast<int>(line), "", what);
}

// Whole numbers only: "3" reads, "3x", "-1" and "" do not.
std::optional<std::size_t> whole_number(const std::string& text) {
  if (text.empty() || text.size() > 6 || text.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  return static_cast<std::size_t>(std::stoul(text));
}

// The '#' lines: a team (in index order from 0), a robot, a call; anything else is a comment.
void read_comment(const std::string& line, WorldLog& log) {
  const auto cells = split(line);
  if (cells[0] == "#team") {
    if (cells.size() != 4 || cells[2].empty() || (cells[3] != "+x" && cells[3] != "-x")) return;
    if (whole_number(cells[1]) != log.teams.size()) return;
    log.teams.push_back({cells[2], cells[3] == "+x"});
  } else if (cells[0] == "#robot") {
    if (cells.size() != 5) return;
    const auto index = whole_number(cells[1]);
    const auto team = whole_number(cells[2]);
    const auto agent = whole_number(cells[3]);
    if (!index || !team || !agent || *index >= log.robot_info.size() || cells[4].empty()) return;
    log.robot_info[*index] = {*team, static_cast<int>(*agent), cells[4]};
  } else if (cells[0] == "#referee") {
    if (cells.size() < 6) return;
    char* end = nullptr;
    const double t = std::strtod(cells[1].c_str(), &end);
    if (end != cells[1].c_str() + cells[1].size() || !std::isfinite(t)) return;
    WorldLogCall c;
    c.time_s = t;
    c.restart = cells[2];
    c.team = cells[3];
    c.spot_x_m = std::strtod(cells[4].c_str(), nullptr);
    c.spot_y_m = std::strtod(cells[5].c_str(), nullptr);
    c.score.assign(cells.begin() + 6, cells.end());
    log.calls.push_back(std::move(c));
  }
}

}  // namespace

WorldLogWriter::WorldLogWriter(Nanos period, const std::vector<WorldLogTeam>& teams,
                               const std::vector<WorldLogRobot>& robots)
    : period_(period) {
  text_ = "time_s,ball_x_m,ball_y_m,ball_z_m";
  for (std::size_t r = 0; r < robots.size(); ++r) {
    const std::string p = "robot" + std::to_string(r) + "_";
    text_ += "," + p + "x_m," + p + "y_m," + p + "heading_deg," + p + "reported_x_m," + p + "reported_y_m," + p +
             "reported_heading_deg";
  }
  text_ += '\n';
  if (teams.size() > 1) {
    // Who played for whom, for a replay; one team's logs stay as they always were.
    for (std::size_t t = 0; t < teams.size(); ++t) {
      text_ +=
          "#team," + std::to_string(t) + "," + teams[t].name + "," + (teams[t].attacks_positive_x ? "+x" : "-x") + "\n";
    }
    for (std::size_t r = 0; r < robots.size(); ++r) {
      text_ += "#robot," + std::to_string(r) + "," + std::to_string(robots[r].team) + "," +
               std::to_string(robots[r].agent) + "," + robots[r].interface + "\n";
    }
  }
}

void WorldLogWriter::begin_row(Nanos now, const Eigen::Vector3d& ball) {
  next_ = now + period_;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.3f,%.4f,%.4f,%.4f", to_seconds(now), ball.x(), ball.y(), ball.z());
  text_ += buf;
}

void WorldLogWriter::robot(const kinematics::Pose& p, const kinematics::Pose& reported) {
  char buf[160];
  std::snprintf(buf, sizeof buf, ",%.4f,%.4f,%.2f,%.4f,%.4f,%.2f", p.x_m, p.y_m, p.heading_rad * 180 / M_PI,
                reported.x_m, reported.y_m, reported.heading_rad * 180 / M_PI);
  text_ += buf;
}

void WorldLogWriter::call(const WorldLogCall& call) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "#referee,%.3f,%s,%s,%.3f,%.3f", call.time_s, call.restart.c_str(), call.team.c_str(),
                call.spot_x_m, call.spot_y_m);
  text_ += buf;
  for (const std::string& goals : call.score) text_ += "," + goals;
  text_ += '\n';
}

WorldLog read_world_log(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw SetupError("cannot read the world log " + path.string());
  WorldLog log;
  std::string line;
  std::getline(in, line);
  log.columns = split(line);
  const std::vector<std::string> first = {"time_s", "ball_x_m", "ball_y_m", "ball_z_m"};
  if (log.columns.size() < first.size() || !std::equal(first.begin(), first.end(), log.columns.begin())) {
    refuse(path, 1,
           "not a world log: its header starts time_s,ball_x_m,ball_y_m,ball_z_m (write one with canhil run "
           "--virtual-time --world-log FILE)");
  }
  std::size_t& robots = log.robots;
  while (robots < 1000 && std::find(log.columns.begin(), log.columns.end(),
                                    "robot" + std::to_string(robots) + "_x_m") != log.columns.end()) {
    ++robots;
  }
  if (log.columns.size() != first.size() + 6 * robots) {
    refuse(path, 1,
           "expected 4 columns and 6 per robot, got " + std::to_string(log.columns.size()) + " for " +
               std::to_string(robots) + " robot(s)");
  }
  for (std::size_t r = 0; r < robots; ++r)
    log.robot_info.push_back({0, static_cast<int>(r + 1), "robot " + std::to_string(r)});
  std::size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    if (line[0] == '#') {
      read_comment(line, log);
      continue;
    }
    const auto cells = split(line);
    if (cells.size() != log.columns.size()) {
      refuse(path, number,
             std::to_string(cells.size()) + " values where the header has " + std::to_string(log.columns.size()));
    }
    std::vector<double> row;
    row.reserve(cells.size());
    for (const std::string& c : cells) {
      char* end = nullptr;
      const double v = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size() || !std::isfinite(v)) {
        refuse(path, number, "'" + c + "' is not a number");
      }
      row.push_back(v);
    }
    if (!log.rows.empty() && row[0] < log.rows.back()[0]) {
      refuse(path, number, "time goes back; a world log is in time order");
    }
    log.rows.push_back(std::move(row));
  }
  if (log.rows.empty()) refuse(path, 0, "the world log has no rows");
  // A robot of a team the log does not name is of no team it knows: the first.
  for (WorldLogRobot& r : log.robot_info) {
    if (r.team >= std::max<std::size_t>(1, log.teams.size())) r.team = 0;
  }
  return log;
}

}  // namespace canhil::emulator
