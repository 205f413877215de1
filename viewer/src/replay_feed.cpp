#include "canhil/viewer/replay_feed.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>

#include "canhil/base/located_error.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/goal_watcher.hpp"
#include "canhil/emulator/world_log.hpp"
#include "canhil/frames/describe.hpp"
#include "canhil/viewer/live_feed.hpp"
#include "http_paths.hpp"

namespace canhil::viewer {
namespace {

using nlohmann::json;

// A trace whose clock is the wall's (a capture) starts at its first frame; a virtual-time trace at 0.
constexpr double kWallClockTrace = 1e6;

// A jump in ball speed between two rows that counts as a kick, without a trace to say so.
constexpr double kKickSpeedJump = 1.5;

}  // namespace

ReplayFeed::ReplayFeed(const std::filesystem::path& world_log, std::optional<std::filesystem::path> trace,
                       physics::WorldParams world, std::shared_ptr<const frames::MessageSet> messages)
    : world_(std::move(world)), messages_(std::move(messages)) {
  emulator::WorldLog log = emulator::read_world_log(world_log);
  columns_ = std::move(log.columns);
  rows_ = std::move(log.rows);
  robots_ = log.robots;
  teams_ = std::move(log.teams);
  robot_info_ = std::move(log.robot_info);
  for (const emulator::WorldLogCall& c : log.calls) {
    std::string text = c.restart + (c.team == "-" ? std::string() : " for " + c.team);
    for (std::size_t k = 0; k < c.score.size(); ++k) text += (k == 0 ? ", score " : ":") + c.score[k];
    events_.push_back({c.time_s, "referee", std::move(text), std::nullopt});
  }
  std::string line;
  if (trace) {
    std::ifstream t(*trace);
    if (!t) throw SetupError("cannot read the trace " + trace->string());
    std::size_t number = 0;
    while (std::getline(t, line)) {
      ++number;
      if (line.empty()) continue;
      frames::LogEntry e;
      std::string why;
      if (!frames::parse_log_line(line, e, &why)) {
        throw LocatedError(trace->string(), static_cast<int>(number), "",
                           why + " (a candump -l log, as canhil run --trace writes)");
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
    const emulator::WorldLogRobot& info = robot_info_[r];
    robots.push_back({{"index", r}, {"agent", info.agent}, {"interface", info.interface}, {"team", info.team}});
  }
  h["robots"] = robots;
  json teams = json::array();  // as live: none said, one team
  for (const emulator::WorldLogTeam& t : teams_)
    teams.push_back({{"name", t.name}, {"attacks_positive_x", t.attacks_positive_x}});
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
