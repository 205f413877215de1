#include "canhil/emulator/goal_watcher.hpp"

#include <cmath>

namespace canhil::emulator {

bool ball_in_goal(const physics::WorldParams& world, const Eigen::Vector3d& b) noexcept {
  const auto& f = world.field;
  const double r = world.ball.radius_m;
  return std::fabs(b.x()) > f.length_m / 2 + r && std::fabs(b.y()) < f.goal.width_m / 2 && b.z() < f.goal.height_m &&
         std::fabs(b.x()) < f.length_m / 2 + f.goal.depth_m + r;
}

std::optional<bool> GoalWatcher::step(const physics::World& world, Nanos now, bool in_play) {
  const Eigen::Vector3d b = world.ball_position();
  const bool in = ball_in_goal(params_, b);
  const bool entered = in && !in_;
  in_ = in;
  if (!entered) return std::nullopt;
  if (in_play) goals_.push_back(Goal{now, b.x() > 0});
  return b.x() > 0;
}

}  // namespace canhil::emulator
