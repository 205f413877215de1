#include "canhil/vision_emu/runner.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace canhil::vision_emu
