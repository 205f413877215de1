#include "canhil/emulator/referee.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>

namespace canhil::emulator {
namespace {

// Each restart's name in the game states, and in the calls' texts, in the
// order of Restart.
struct RestartNames {
  std::string_view name;
  const char* words;
};
constexpr RestartNames kRestartNames[] = {{"kickoff", "kick-off"},
                                          {"throwin", "throw-in"},
                                          {"corner", "corner"},
                                          {"goalkick", "goal kick"},
                                          {"drop_ball", "dropped ball"}};
static_assert(std::size(kRestartNames) == static_cast<std::size_t>(Restart::kDroppedBall) + 1, "a name per restart");

const char* restart_words(Restart r) noexcept { return kRestartNames[static_cast<std::size_t>(r)].words; }

}  // namespace

std::string_view restart_name(Restart r) noexcept { return kRestartNames[static_cast<std::size_t>(r)].name; }

Referee::Referee(const physics::WorldParams& world, std::vector<RefereeTeam> teams, RefereeRules rules,
                 std::uint64_t seed)
    : world_(world),
      teams_(std::move(teams)),
      rules_(rules),
      rng_(seed ^ 0x5EFE5EEDULL),  // its own stream: the faults' draws stay as they were
      score_(teams_.size(), 0) {}

std::optional<std::size_t> Referee::team_of_robot(std::size_t robot) const {
  for (std::size_t t = 0; t < teams_.size(); ++t) {
    if (robot >= teams_[t].first_robot && robot < teams_[t].first_robot + teams_[t].robots) return t;
  }
  return std::nullopt;
}

std::optional<std::size_t> Referee::attacking(bool positive_x) const {
  for (std::size_t t = 0; t < teams_.size(); ++t) {
    if (teams_[t].attacks_positive_x == positive_x) return t;
  }
  return std::nullopt;
}

std::optional<std::size_t> Referee::defending(bool positive_x) const { return attacking(!positive_x); }

std::optional<std::size_t> Referee::other(std::optional<std::size_t> team) {
  if (!team) {  // nobody touched it: a draw
    if (teams_.empty()) return std::nullopt;
    return static_cast<std::size_t>(rng_() % teams_.size());
  }
  if (teams_.size() < 2) return std::nullopt;  // the opponent canhil does not play
  return 1 - *team;
}

std::string Referee::state_for(const RefereeCall& call, std::size_t team) const {
  if (call.restart == Restart::kDroppedBall) return "drop_ball";
  return std::string(call.team && *call.team == team ? "our_" : "their_") + std::string(restart_name(call.restart));
}

RefereeCall& Referee::call(RefereeCall c, Nanos now) {
  c.time = now;
  calls_.push_back(std::move(c));
  resume_at_ = now + from_seconds(rules_.restart_pause_s);
  taken_from_.reset();
  still_ = false;
  return calls_.back();
}

bool Referee::ball_in_play_at(const Eigen::Vector2d& ball) const noexcept {
  if (resume_at_) return false;
  return !taken_from_ || (ball - *taken_from_).norm() >= rules_.in_play_distance_m;
}

bool Referee::resume_due(Nanos now) {
  if (!resume_at_ || now < *resume_at_) return false;
  resume_at_.reset();
  taken_from_ = ball_;
  return true;
}

// The ball entered a goal before the restart was taken (it was not in play):
// no goal; the same restart again, the ball back on its spot.
RefereeCall& Referee::retake(bool goal_positive_x, Nanos now) {
  RefereeCall c = calls_.back();  // there is one: the ball is out of play only after a call
  c.scorer.reset();
  c.goal_positive_x = false;
  const char* restart = restart_words(c.restart);
  std::string taker;  // a dropped ball is nobody's
  if (c.restart != Restart::kDroppedBall) taker = " " + (c.team ? teams_[*c.team].name : std::string("the opponent"));
  char text[160];
  std::snprintf(text, sizeof text, "ball into the %s goal before the %s was taken: no goal, %s%s again at (%.2f, %.2f)",
                goal_positive_x ? "+x" : "-x", restart, restart, taker.c_str(), c.spot.x(), c.spot.y());
  c.text = text;
  return call(std::move(c), now);
}

std::optional<RefereeCall> Referee::step(const RefereeView& view, Nanos now, std::optional<bool> goal_positive_x) {
  const auto& f = world_.field;
  const double r = world_.ball.radius_m;
  const auto name = [this](std::optional<std::size_t> t) { return t ? teams_[*t].name : std::string("the opponent"); };
  // Who touched it last: the nearest robot within reach of a ball on the ground.
  if (view.ball.z() < 2 * r) {
    const double reach = world_.robot.body_radius_m + r + rules_.touch_distance_m;
    double nearest = reach;
    for (std::size_t k = 0; k < view.robots.size(); ++k) {
      const double d = (view.robots[k] - view.ball.head<2>()).norm();
      if (d < nearest) {
        nearest = d;
        last_touch_ = team_of_robot(k);
      }
    }
  }
  ball_ = view.ball.head<2>();
  if (taken_from_ && ball_in_play_at(ball_)) taken_from_.reset();  // the restart is taken: the ball in play
  if (goal_positive_x) {
    if (!ball_in_play()) return retake(*goal_positive_x, now);
    const std::optional<std::size_t> scorer = attacking(*goal_positive_x);
    if (scorer) ++score_[*scorer];
    if (!rules_.kickoff_after_goal) return std::nullopt;
    RefereeCall c;
    c.restart = Restart::kKickoff;
    c.scorer = scorer;
    c.goal_positive_x = *goal_positive_x;
    c.team = defending(*goal_positive_x);  // who conceded kicks off
    char score[64] = "";
    if (teams_.size() == 2) std::snprintf(score, sizeof score, " (%d:%d)", score_[0], score_[1]);
    c.text = "goal for " + name(scorer) + " in the " + (*goal_positive_x ? "+x" : "-x") + " goal" + score +
             ", kick-off " + name(c.team);
    return call(std::move(c), now);
  }
  if (resume_at_) return std::nullopt;  // a restart is being taken
  if (rules_.out_of_play) {
    if (auto c = out_of_play(view, now)) return c;
  }
  if (rules_.dropped_ball) {
    if (!still_ || (view.ball.head<2>() - still_at_).norm() > rules_.stuck_radius_m) {
      still_ = true;  // the ball went somewhere: watch it from here
      still_since_ = now;
      still_at_ = view.ball.head<2>();
    } else if (now - still_since_ >= from_seconds(rules_.stuck_s)) {
      RefereeCall c;
      c.restart = Restart::kDroppedBall;
      c.spot = {std::clamp(view.ball.x(), -f.length_m / 2 + 1, f.length_m / 2 - 1),
                std::clamp(view.ball.y(), -f.width_m / 2 + 1, f.width_m / 2 - 1)};
      char text[96];
      std::snprintf(text, sizeof text, "stuck for %.0f s: dropped ball at (%.2f, %.2f)", rules_.stuck_s, c.spot.x(),
                    c.spot.y());
      c.text = text;
      return call(std::move(c), now);
    }
  }
  return std::nullopt;
}

std::optional<RefereeCall> Referee::out_of_play(const RefereeView& view, Nanos now) {
  const auto& f = world_.field;
  const double r = world_.ball.radius_m;
  const double x = view.ball.x();
  const double y = view.ball.y();
  const auto name = [this](std::optional<std::size_t> t) { return t ? teams_[*t].name : std::string("the opponent"); };
  const double sx = x > 0 ? 1.0 : -1.0;
  const double sy = y > 0 ? 1.0 : -1.0;
  char text[160];
  if (std::fabs(y) > f.width_m / 2 + r) {  // wholly over a touch line
    RefereeCall c;
    c.restart = Restart::kThrowIn;
    c.team = other(last_touch_);
    c.spot = {std::clamp(x, -f.length_m / 2, f.length_m / 2), sy * f.width_m / 2};
    std::snprintf(text, sizeof text, "out over the %s touch line: throw-in %s at (%.2f, %.2f)", y > 0 ? "+y" : "-y",
                  name(c.team).c_str(), c.spot.x(), c.spot.y());
    c.text = text;
    return call(std::move(c), now);
  }
  const bool in_goal = std::fabs(y) < f.goal.width_m / 2 && view.ball.z() < f.goal.height_m;
  if (std::fabs(x) > f.length_m / 2 + r && !in_goal) {  // over a goal line, beside the goal
    const std::optional<std::size_t> defender = defending(x > 0);
    RefereeCall c;
    if (last_touch_ && last_touch_ == defender) {
      c.restart = Restart::kCorner;
      c.team = attacking(x > 0);
      c.spot = {sx * f.length_m / 2, sy * f.width_m / 2};
    } else {
      c.restart = Restart::kGoalKick;
      c.team = defender;
      c.spot = {sx * (f.length_m / 2 - f.goal_area_depth_m), sy * f.goal_area_width_m / 2};
    }
    std::snprintf(text, sizeof text, "out over the %s goal line: %s %s at (%.2f, %.2f)", x > 0 ? "+x" : "-x",
                  c.restart == Restart::kCorner ? "corner" : "goal kick", name(c.team).c_str(), c.spot.x(), c.spot.y());
    c.text = text;
    return call(std::move(c), now);
  }
  return std::nullopt;
}

}  // namespace canhil::emulator
