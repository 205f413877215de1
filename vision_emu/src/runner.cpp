#include "canhil/vision_emu/runner.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"

namespace canhil::vision_emu {

Scene snapshot(const physics::World& world) {
  Scene s;
  snapshot(world, s);
  return s;
}

void snapshot(const physics::World& world, Scene& s) {
  s.robots.clear();
  s.obstacles.clear();
  s.time_s = world.time_s();
  s.robot_radius_m = world.params().robot.body_radius_m;
  for (std::size_t i = 0; i < world.robot_count(); ++i) s.robots.push_back(world.robot(i).pose());
  for (std::size_t i = 0; i < world.obstacle_count(); ++i) {
    s.obstacles.push_back({world.obstacle_position(i).head<2>(), world.obstacle_params(i).radius_m});
  }
  s.ball = world.ball_position();
  s.ball_radius_m = world.params().ball.radius_m;
}

VisionRunner::VisionRunner(std::vector<Vision> per_robot, Sink sink)
    : vision_(std::move(per_robot)), sink_(std::move(sink)) {
  for (std::size_t i = 0; i < vision_.size(); ++i) {
    next_frame_s_.push_back(0.0);
    rng_.emplace_back(vision_[i].params().seed + static_cast<unsigned>(i) * 7919u);
  }
  frame_.resize(vision_.size());
}

void VisionRunner::on_step(const physics::World& world) {
  Scene fresh;
  if (!spare_.empty()) {
    fresh = std::move(spare_.back());
    spare_.pop_back();
  }
  snapshot(world, fresh);
  history_.push_back(std::move(fresh));
  const double now = world.time_s();
  double longest = 0;
  for (const Vision& v : vision_) longest = std::max(longest, v.params().latency_s);
  while (history_.size() > 2 && history_[1].time_s <= now - longest - 1e-9) {
    spare_.push_back(std::move(history_.front()));
    history_.pop_front();
  }
  for (std::size_t r = 0; r < vision_.size() && r < world.robot_count(); ++r) {
    if (now + 1e-9 < next_frame_s_[r]) continue;
    next_frame_s_[r] += 1.0 / vision_[r].params().frame_rate_hz;
    if (next_frame_s_[r] < now) next_frame_s_[r] = now + 1.0 / vision_[r].params().frame_rate_hz;
    // The newest snapshot not newer than now - latency.
    const double want = now - vision_[r].params().latency_s;
    const Scene* scene = &history_.front();
    for (std::size_t i = 0; i < history_.size(); ++i) {
      if (history_[i].time_s <= want + 1e-9) scene = &history_[i];
    }
    vision_[r].see(*scene, r, rng_[r], frame_[r]);
    sink_(r, frame_[r], scene->time_s);
    ++frames_;
  }
}

void write_vision_info(int agent, const VisionFrame& f) {
  auto info = std::make_unique<VisionInfo>();
  auto fill = [](PointList& list, const std::vector<Eigen::Vector2d>& pts) {
    list.nPoints = static_cast<int>(std::min<std::size_t>(pts.size(), MAX_POINTS));
    for (int i = 0; i < list.nPoints; ++i) {
      list.point[i] = {static_cast<float>(pts[static_cast<std::size_t>(i)].x()),
                       static_cast<float>(pts[static_cast<std::size_t>(i)].y())};
    }
  };
  fill(info->obstacles, f.obstacles);
  fill(info->linePoints, f.lines);
  info->nBalls = static_cast<int>(std::min<std::size_t>(f.balls.size(), MAX_BALLS));
  for (int i = 0; i < info->nBalls; ++i) {
    info->ball[i] = {static_cast<float>(f.balls[static_cast<std::size_t>(i)].x()),
                     static_cast<float>(f.balls[static_cast<std::size_t>(i)].y())};
  }
  DB_put_in(agent, agent, VISION_INFO, info.get(), 0);
}

VisionRunner::Sink rtdb_sink(std::vector<int> agent_of_robot) {
  return [agents = std::move(agent_of_robot)](std::size_t robot, const VisionFrame& f, double) {
    if (robot >= agents.size()) return;
    write_vision_info(agents[robot], f);
    DB_signal_frame(agents[robot]);
  };
}

}  // namespace canhil::vision_emu
