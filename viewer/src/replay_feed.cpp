#include "canhil/viewer/replay_feed.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/goal_watcher.hpp"
#include "canhil/frames/describe.hpp"
#include "canhil/viewer/live_feed.hpp"
#include "http_paths.hpp"

namespace canhil::viewer {
namespace {

using nlohmann::json;

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

std::string where(const std::filesystem::path& file, std::size_t line) {
  return file.string() + ":" + std::to_string(line) + ": ";
}

// A trace whose clock is the wall's (a capture) starts at its first frame; a virtual-time trace at 0.
constexpr double kWallClockTrace = 1e6;

// A jump in ball speed between two rows that counts as a kick, without a trace to say so.
constexpr double kKickSpeedJump = 1.5;

}  // namespace

ReplayFeed::ReplayFeed(const std::filesystem::path& world_log, std::optional<std::filesystem::path> trace,
                       physics::WorldParams world, std::shared_ptr<const frames::MessageSet> messages)
    : world_(std::move(world)), messages_(std::move(messages)) {
  std::ifstream in(world_log);
  if (!in) throw SetupError("cannot read the world log " + world_log.string());
  std::string line;
  std::getline(in, line);
  columns_ = split(line);
  const std::vector<std::string> first = {"time_s", "ball_x_m", "ball_y_m", "ball_z_m"};
  if (columns_.size() < first.size() || !std::equal(first.begin(), first.end(), columns_.begin())) {
    throw SetupError(where(world_log, 1) +
                     "not a world log: its header starts time_s,ball_x_m,ball_y_m,ball_z_m (write one with canhil run "
                     "--virtual-time --world-log FILE)");
  }
  while (robots_ < 1000 &&
         std::find(columns_.begin(), columns_.end(), "robot" + std::to_string(robots_) + "_x_m") != columns_.end()) {
    ++robots_;
  }
  if (columns_.size() != first.size() + 6 * robots_) {
    throw SetupError(where(world_log, 1) + "expected 4 columns and 6 per robot, got " +
                     std::to_string(columns_.size()) + " for " + std::to_string(robots_) + " robot(s)");
  }
  for (std::size_t r = 0; r < robots_; ++r)
    robot_info_.push_back({0, static_cast<int>(r + 1), "robot " + std::to_string(r)});
  std::size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    if (line[0] == '#') {
      // A referee's call, a team or a robot; other comments are skipped.
      referee_line(line);
      team_line(line);
      robot_line(line);
      continue;
    }
    const auto cells = split(line);
    if (cells.size() != columns_.size()) {
      throw SetupError(where(world_log, number) + std::to_string(cells.size()) + " values where the header has " +
                       std::to_string(columns_.size()));
    }
    std::vector<double> row;
    for (const std::string& c : cells) {
      char* end = nullptr;
      const double v = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size() || !std::isfinite(v)) {
        throw SetupError(where(world_log, number) + "'" + c + "' is not a number");
      }
      row.push_back(v);
    }
    if (!rows_.empty() && row[0] < rows_.back()[0]) {
      throw SetupError(where(world_log, number) + "time goes back; a world log is in time order");
    }
    rows_.push_back(std::move(row));
  }
  if (rows_.empty()) throw SetupError(world_log.string() + ": the world log has no rows");
  // A robot of a team the log does not name is of no team it knows: the first.
  for (ReplayRobot& r : robot_info_) {
    if (r.team >= std::max<std::size_t>(1, teams_.size())) r.team = 0;
  }
  if (trace) {
    std::ifstream t(*trace);
    if (!t) throw SetupError("cannot read the trace " + trace->string());
    number = 0;
    while (std::getline(t, line)) {
      ++number;
      if (line.empty()) continue;
      frames::LogEntry e;
      std::string why;
      if (!frames::parse_log_line(line, e, &why)) {
        throw SetupError(where(*trace, number) + why + " (a candump -l log, as canhil run --trace writes)");
      }
      trace_.push_back(std::move(e));
    }
    std::stable_sort(trace_.begin(), trace_.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
    if (!trace_.empty() && to_seconds(trace_.front().time) > kWallClockTrace) {
      const Nanos start = trace_.front().time;
      for (frames::LogEntry& e : trace_) e.time -= start;
    }
  }
  find_goals();
  find_kicks();
  std::sort(events_.begin(), events_.end(), [](const auto& a, const auto& b) { return a.time_s < b.time_s; });
  json events = json::array();
  for (const ReplayEvent& e : events_) {
    json event{{"time_s", e.time_s}, {"kind", e.kind}, {"text", e.text}};
    if (e.positive_x) event["positive_x"] = *e.positive_x;
    events.push_back(std::move(event));
  }
  replay_json_ = json{{"columns", columns_}, {"robots", robots_}, {"rows", rows_}, {"events", events}}.dump();
}

// "#referee,TIME,RESTART,TEAM,X,Y,SCORE..." (Session::log_call): a mark on
// the scrubber. A line that does not read so is a comment like any other.
void ReplayFeed::referee_line(const std::string& line) {
  const auto cells = split(line);
  if (cells.size() < 6 || cells[0] != "#referee") return;
  char* end = nullptr;
  const double t = std::strtod(cells[1].c_str(), &end);
  if (end != cells[1].c_str() + cells[1].size() || !std::isfinite(t)) return;
  std::string text = cells[2] + (cells[3] == "-" ? std::string() : " for " + cells[3]);
  if (cells.size() > 6) {
    text += ", score";
    for (std::size_t k = 6; k < cells.size(); ++k) text += (k == 6 ? " " : ":") + cells[k];
  }
  events_.push_back({t, "referee", std::move(text), std::nullopt});
}

namespace {
// Whole numbers only: "3" reads, "3x", "-1" and "" do not.
std::optional<std::size_t> whole_number(const std::string& text) {
  if (text.empty() || text.size() > 6 || text.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  return static_cast<std::size_t>(std::stoul(text));
}
}  // namespace

// "#team,INDEX,NAME,+x|-x" (Session's world log with two teams), in index
// order from 0. A line that does not read so is a comment like any other.
void ReplayFeed::team_line(const std::string& line) {
  const auto cells = split(line);
  if (cells.size() != 4 || cells[0] != "#team" || cells[2].empty() || (cells[3] != "+x" && cells[3] != "-x")) return;
  if (whole_number(cells[1]) != teams_.size()) return;
  teams_.push_back({cells[2], cells[3] == "+x"});
}

// "#robot,INDEX,TEAM,AGENT,INTERFACE".
void ReplayFeed::robot_line(const std::string& line) {
  const auto cells = split(line);
  if (cells.size() != 5 || cells[0] != "#robot") return;
  const auto index = whole_number(cells[1]);
  const auto team = whole_number(cells[2]);
  const auto agent = whole_number(cells[3]);
  if (!index || !team || !agent || *index >= robot_info_.size() || cells[4].empty()) return;
  robot_info_[*index] = {*team, static_cast<int>(*agent), cells[4]};
}

// GoalWatcher's rule, on the logged ball.
void ReplayFeed::find_goals() {
  bool was_in = false;
  for (const auto& row : rows_) {
    const double x = row[1];
    const bool in = emulator::ball_in_goal(world_, {x, row[2], row[3]});
    if (in && !was_in) {
      events_.push_back({row[0], "goal", x > 0 ? "goal in the +x goal" : "goal in the -x goal", x > 0});
    }
    was_in = in;
  }
}

void ReplayFeed::find_kicks() {
  if (!trace_.empty()) {
    // The laptop's kick orders (M7 with a power): what the agent asked for.
    const frames::MessageCodec* m7 = messages_->codec().find("M7");
    for (const frames::LogEntry& e : trace_) {
      if (m7 == nullptr || e.frame.id != m7->id() || e.frame.kind != frames::FrameKind::kData) continue;
      frames::M7 k{};
      if (messages_->m7.decode(e.frame, k).status != frames::DecodeStatus::kOk) continue;
      if ((k.kick & 0x7F) == 0) continue;
      events_.push_back({to_seconds(e.time), "kick",
                         e.iface + " kick, power " + std::to_string(k.kick & 0x7F) + ((k.kick & 0x80) ? " (low)" : ""),
                         std::nullopt});
    }
    return;
  }
  for (std::size_t i = 1; i < rows_.size(); ++i) {
    const auto speed = [&](std::size_t k) {
      const double dt = rows_[k][0] - rows_[k - 1][0];
      if (dt <= 0) return 0.0;
      return std::hypot(rows_[k][1] - rows_[k - 1][1], rows_[k][2] - rows_[k - 1][2]) / dt;
    };
    if (i >= 2 && speed(i) - speed(i - 1) > kKickSpeedJump) {
      events_.push_back({rows_[i][0], "kick", "the ball sped up (a kick?)", std::nullopt});
    }
  }
}

json ReplayFeed::hello() {
  json h = world_hello(world_);
  h["mode"] = "replay";
  json robots = json::array();
  for (std::size_t r = 0; r < robots_; ++r) {
    const ReplayRobot& info = robot_info_[r];
    robots.push_back({{"index", r}, {"agent", info.agent}, {"interface", info.interface}, {"team", info.team}});
  }
  h["robots"] = robots;
  json teams = json::array();  // as live: none said, one team
  for (const ReplayTeam& t : teams_) teams.push_back({{"name", t.name}, {"attacks_positive_x", t.attacks_positive_x}});
  h["teams"] = teams;
  h["obstacles"] = json::array();
  h["virtual_time"] = false;
  h["duration_s"] = rows_.back()[0];
  h["has_trace"] = !trace_.empty();
  h["rows"] = rows_.size();
  return h;
}

json ReplayFeed::request(std::string_view) {
  return {{"ok", false},
          {"error", "a replay takes no commands; it is played in the page (canhil run changes a world)"}};
}

json ReplayFeed::frames_between(double from_s, double to_s, std::size_t most) const {
  json out = json::array();
  const auto first = std::lower_bound(trace_.begin(), trace_.end(), from_seconds(from_s),
                                      [](const frames::LogEntry& e, Nanos t) { return e.time < t; });
  for (auto it = first; it != trace_.end() && to_seconds(it->time) <= to_s && out.size() < most; ++it) {
    const frames::Described d = frames::describe(messages_->codec(), it->frame);
    out.push_back({{"time_s", to_seconds(it->time)},
                   {"interface", it->iface},
                   {"id", it->frame.id},
                   {"name", d.message != nullptr ? std::string(d.message->name()) : std::string()},
                   {"data", frames::format_compact(it->frame)},
                   {"signals", frames::describe_text(it->frame, d)}});
  }
  return out;
}

std::optional<std::string> ReplayFeed::api(std::string_view path, std::string_view query) {
  if (path == "replay") return replay_json_;
  if (path == "frames") {
    const std::string target = "?" + std::string(query);
    const auto number = [&](const char* key, double fallback) {
      const std::string v = query_value(target, key);
      char* end = nullptr;
      const double d = std::strtod(v.c_str(), &end);
      return v.empty() || end != v.c_str() + v.size() || !std::isfinite(d) ? fallback : d;
    };
    const double from = number("from", 0);
    return frames_between(from, std::max(from, number("to", from + 0.1))).dump();
  }
  return std::nullopt;
}

}  // namespace canhil::viewer
