// canhil/emulator/referee.hpp — the referee of a match: goals per team, the
// restarts after them (a kick-off for the team that conceded), a ball out over
// a line put back at the nearest restart spot (throw-in, corner or goal kick
// for the right team), a stuck game restarted with a dropped ball. It watches
// what the world shows after each step and calls; Session carries the call
// out (the ball to the spot, the robots back to their places at a kick-off,
// each team's coach state "our_X" / "their_X", then "start" after the pause).
// The ball is in play again only once the restart is taken: after "start",
// the ball moved in_play_distance_m from where it lay. A ball that enters a
// goal before (in the pause, say) scores nothing: the restart is taken again.
// Seeded: where it cannot tell who touched the ball last, a draw decides.
//
// Thread-compatible: used by the thread that steps the world.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/physics/params.hpp"

namespace canhil::emulator {

/// The referee's rules ([referee] in a scenario); each can be switched off.
struct RefereeRules {
  std::optional<bool> enabled;      ///< default: on with two teams, off otherwise
  bool kickoff_after_goal = true;   ///< ball to the centre, robots to their places, kick-off for who conceded
  bool out_of_play = true;          ///< throw-ins, corners and goal kicks
  bool dropped_ball = true;         ///< a stuck game restarted at the ball
  double stuck_s = 10.0;            ///< the ball within stuck_radius_m of one spot this long: stuck
  double stuck_radius_m = 0.5;      ///< (two robots pushing it to and fro do not unstick it)
  double restart_pause_s = 2.0;     ///< the restart's states held this long (robots take their places), then "start"
  double touch_distance_m = 0.05;   ///< a robot this close to the ball (beyond both radii) touches it
  double restart_distance_m = 1.0;  ///< at a restart other than a kick-off, robots nearer the spot step back this far
  double in_play_distance_m = 0.5;  ///< after "start", the ball moved this far: the restart is taken, the ball in play
};

enum class Restart { kKickoff, kThrowIn, kCorner, kGoalKick, kDroppedBall };

/// "kickoff", "throwin", "corner", "goalkick", "drop_ball" (as in the game states).
std::string_view restart_name(Restart r) noexcept;

/// One decision of the referee.
struct RefereeCall {
  Nanos time{0};
  Restart restart = Restart::kKickoff;
  std::optional<std::size_t> team;                 ///< the team that takes it (none: a dropped ball, or no such team)
  std::optional<std::size_t> scorer;               ///< after a goal: the team that attacks that goal, if any
  bool goal_positive_x = false;                    ///< after a goal: which one
  Eigen::Vector2d spot = Eigen::Vector2d::Zero();  ///< where the ball goes
  std::string text;                                ///< for people: "goal for new (+x), kick-off old"
};

/// What the referee sees after a step.
struct RefereeView {
  Eigen::Vector3d ball = Eigen::Vector3d::Zero();
  Eigen::Vector3d ball_velocity = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector2d> robots;  ///< every robot's centre, in the scenario's order
};

/// A team as the referee needs it.
struct RefereeTeam {
  std::string name;
  bool attacks_positive_x = true;
  std::size_t first_robot = 0;
  std::size_t robots = 0;
};

class Referee {
 public:
  Referee(const physics::WorldParams& world, std::vector<RefereeTeam> teams, RefereeRules rules, std::uint64_t seed);

  /// After a step at `now`; `goal` when the ball entered a goal in it (and
  /// on which side): a goal if the ball is in play (ball_in_play_at the
  /// view's ball), else the last restart taken again. The call made, if any.
  std::optional<RefereeCall> step(const RefereeView& view, Nanos now, std::optional<bool> goal_positive_x);
  /// True once, at the first step after a call's pause is over: play on
  /// ("start"); the restart is taken once the ball moves from where it lies.
  bool resume_due(Nanos now);

  /// No restart's pause is running (play goes on, the restart taken or not).
  bool in_play() const noexcept { return !resume_at_.has_value(); }
  /// The ball is in play: no call yet, or the last one's restart was taken
  /// (after "start", the ball moved in_play_distance_m). Only then does a ball
  /// entering a goal score.
  bool ball_in_play() const noexcept { return !resume_at_ && !taken_from_; }
  /// Whether the ball is in play once it is at `ball`: it was, or the move there takes the restart.
  bool ball_in_play_at(const Eigen::Vector2d& ball) const noexcept;
  /// Goals per team (a goal in a goal no team attacks counts for nobody).
  const std::vector<int>& score() const noexcept { return score_; }
  const std::vector<RefereeCall>& calls() const noexcept { return calls_; }
  /// The team of the robot that touched the ball last, if any did.
  std::optional<std::size_t> last_touch() const noexcept { return last_touch_; }
  const RefereeRules& rules() const noexcept { return rules_; }
  /// The game state a call gives team t: "our_X" for the taker, "their_X" for the other, "drop_ball".
  std::string state_for(const RefereeCall& call, std::size_t team) const;

 private:
  std::optional<std::size_t> team_of_robot(std::size_t robot) const;
  std::optional<std::size_t> other(std::optional<std::size_t> team);  // the taker against `team` (a draw for none)
  std::optional<std::size_t> attacking(bool positive_x) const;
  std::optional<std::size_t> defending(bool positive_x) const;
  std::optional<RefereeCall> out_of_play(const RefereeView& view, Nanos now);
  RefereeCall& retake(bool goal_positive_x, Nanos now);
  RefereeCall& call(RefereeCall c, Nanos now);

  physics::WorldParams world_;
  std::vector<RefereeTeam> teams_;
  RefereeRules rules_;
  std::mt19937_64 rng_;
  std::vector<int> score_;
  std::vector<RefereeCall> calls_;
  std::optional<std::size_t> last_touch_;
  Nanos still_since_{0};
  bool still_ = false;
  Eigen::Vector2d still_at_ = Eigen::Vector2d::Zero();
  std::optional<Nanos> resume_at_;
  Eigen::Vector2d ball_ = Eigen::Vector2d::Zero();  // where the last step saw it
  std::optional<Eigen::Vector2d> taken_from_;       // after "start": where the ball lay, until the restart is taken
};

}  // namespace canhil::emulator
