// canhil/emulator/referee_desk.hpp — the referee's calls carried out in the
// world, on the thread that steps it. The Referee (referee.hpp) decides; the
// desk shows it the world after each step and, at a call, puts the ball on
// its spot and the robots where the rules want them: at a kick-off back to
// their scenario places, at any other restart at least restart_distance_m
// from the spot. The game states each team is told are the session's part.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "canhil/emulator/referee.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::emulator {

class RefereeDesk {
 public:
  /// The referee of `scenario` (complete; it must outlive the desk).
  explicit RefereeDesk(const Scenario& scenario);

  /// What a step brought.
  struct Outcome {
    std::optional<RefereeCall> call;  ///< a call, already carried out in the world
    bool resume = false;              ///< a call's pause is over: play on
  };
  /// After a step at `now` (`goal`: the ball entered a goal in it, on which side;
  /// a goal only when the ball was in play, Referee::step).
  Outcome step(physics::World& world, Nanos now, std::optional<bool> goal_positive_x);

  const Referee& referee() const noexcept { return referee_; }
  /// How many times robot r was put somewhere by a call.
  std::uint32_t placements(std::size_t robot) const { return placements_.at(robot); }

 private:
  void carry_out(physics::World& world, const RefereeCall& call);
  void keep_away_from(physics::World& world, const Eigen::Vector2d& spot);

  const Scenario& scenario_;
  Referee referee_;
  RefereeView view_;  // kept: filled every step
  std::vector<std::uint32_t> placements_;
};

}  // namespace canhil::emulator
