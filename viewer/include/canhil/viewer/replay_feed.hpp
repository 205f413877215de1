// canhil/viewer/replay_feed.hpp — a recorded run for the viewer (`canhil
// view WORLD_LOG [--trace TRACE]`): the world log's rows, who played for
// whom (its "#team" and "#robot" lines, written with two teams; read by
// emulator/world_log.hpp), and the
// events in them (goals from the ball's path; the referee's calls from its
// "#referee" lines; kicks from the laptop's kick commands in
// the trace, or from the ball's jumps in speed without one), and the trace's
// frames around any time, decoded. The page plays it; the feed only serves.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canhil/emulator/world_log.hpp"
#include "canhil/frames/candump.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/physics/params.hpp"
#include "canhil/viewer/server.hpp"

namespace canhil::viewer {

struct ReplayEvent {
  double time_s = 0;
  std::string kind;  ///< "goal" or "kick"
  std::string text;
  std::optional<bool> positive_x;  ///< a goal's side: in the +x goal (as live `goals` say)
};

class ReplayFeed final : public Feed {
 public:
  /// Reads both files; SetupError naming the file and line of a malformed
  /// one (a world log's header must start time_s,ball_x_m,ball_y_m,ball_z_m).
  ReplayFeed(const std::filesystem::path& world_log, std::optional<std::filesystem::path> trace,
             physics::WorldParams world, std::shared_ptr<const frames::MessageSet> messages);

  nlohmann::json hello() override;
  nlohmann::json state() override { return nullptr; }
  nlohmann::json request(std::string_view text) override;
  std::optional<std::string> api(std::string_view path, std::string_view query) override;

  std::size_t robots() const noexcept { return robots_; }
  std::size_t rows() const noexcept { return rows_.size(); }
  const std::vector<ReplayEvent>& events() const noexcept { return events_; }
  /// Empty when the log does not say (one team's logs never do).
  const std::vector<emulator::WorldLogTeam>& teams() const noexcept { return teams_; }
  /// Frames of the trace from `from_s` to `to_s`, at most `most`, as JSON.
  nlohmann::json frames_between(double from_s, double to_s, std::size_t most = kMostFrames) const;
  static constexpr std::size_t kMostFrames = 500;

 private:
  void find_goals();
  void find_kicks();

  physics::WorldParams world_;
  std::shared_ptr<const frames::MessageSet> messages_;
  std::vector<std::string> columns_;
  std::vector<std::vector<double>> rows_;
  std::size_t robots_ = 0;
  std::vector<frames::LogEntry> trace_;  // in time order
  std::vector<ReplayEvent> events_;
  std::vector<emulator::WorldLogTeam> teams_;
  std::vector<emulator::WorldLogRobot> robot_info_;
  std::string replay_json_;  // /api/replay, made once
};

}  // namespace canhil::viewer
