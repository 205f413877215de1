// canhil/emulator/goal_watcher.hpp — goals, step by step (real or virtual time).
#pragma once

#include <optional>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::emulator {

/// The ball entered a goal: wholly past the goal line, between the posts, under the bar.
struct Goal {
  Nanos time{0};
  bool positive_x = true;  ///< the goal at +x (the one the reference agents attack)
};

/// Whether a ball at `ball` is in a goal: wholly past a goal line, between the
/// posts, under the bar, inside the net (the rule GoalWatcher and a replay apply).
bool ball_in_goal(const physics::WorldParams& world, const Eigen::Vector3d& ball) noexcept;

/// Counts the ball's entries into either goal. Used by the thread that steps the world.
class GoalWatcher {
 public:
  explicit GoalWatcher(const physics::WorldParams& world) : params_(world) {}
  /// After a step at `now`: the goal the ball entered in it, if it did (true:
  /// the +x one). The entry is a goal, and counted, only when `in_play` (the
  /// referee's word: no restart is waiting to be taken).
  std::optional<bool> step(const physics::World& world, Nanos now, bool in_play = true);
  const std::vector<Goal>& goals() const noexcept { return goals_; }

 private:
  physics::WorldParams params_;
  std::vector<Goal> goals_;
  bool in_ = false;
};

}  // namespace canhil::emulator
