// The referee on what it is shown: goals per team and the kick-off for who
// conceded, throw-ins, corners and goal kicks for the right team at the right
// spot, a stuck game's dropped ball, the pause before play goes on, no goal
// before a restart is taken, rules switched off, and the seeded draw when
// nobody touched the ball.
#include "canhil/emulator/referee.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "support/counter_watch.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class RefereeTest : public test::WatchedTest {
 protected:
  static std::vector<RefereeTeam> two_teams() { return {{"new", true, 0, 1}, {"old", false, 1, 1}}; }
  // Robot 0 (team new) and robot 1 (team old) where the test puts them; the ball at (x, y) rolling at v.
  static RefereeView view(Eigen::Vector2d ball, Eigen::Vector2d robot0 = {-5, 0}, Eigen::Vector2d robot1 = {5, 0},
                          double v = 1.0) {
    RefereeView w;
    w.ball = {ball.x(), ball.y(), 0.11};
    w.ball_velocity = {v, 0, 0};
    w.robots = {robot0, robot1};
    return w;
  }
  Referee referee(RefereeRules rules = {}, std::uint64_t seed = 1) {
    return Referee(physics::WorldParams{}, two_teams(), rules, seed);
  }
};

TEST_F(RefereeTest, AGoalCountsForTheTeamAttackingItAndWhoConcededKicksOff) {
  Referee ref = referee();
  const auto call = ref.step(view({9.3, 0}), Nanos{1s}, true);
  ASSERT_TRUE(call);
  EXPECT_EQ(ref.score(), (std::vector<int>{1, 0}));
  EXPECT_EQ(call->restart, Restart::kKickoff);
  EXPECT_EQ(call->scorer, 0u);
  EXPECT_EQ(call->team, 1u) << "old conceded";
  EXPECT_EQ(call->spot, Eigen::Vector2d(0, 0));
  EXPECT_EQ(ref.state_for(*call, 1), "our_kickoff");
  EXPECT_EQ(ref.state_for(*call, 0), "their_kickoff");
  EXPECT_NE(call->text.find("goal for new in the +x goal (1:0), kick-off old"), std::string::npos) << call->text;
  // The pause (2 s by default): no play-on before it ends, once after.
  EXPECT_FALSE(ref.resume_due(Nanos{2s}));
  EXPECT_TRUE(ref.resume_due(Nanos{3s}));
  EXPECT_FALSE(ref.resume_due(Nanos{4s}));
  ASSERT_TRUE(ref.step(view({-9.3, 0}), Nanos{5s}, false));
  EXPECT_EQ(ref.score(), (std::vector<int>{1, 1}));
}

TEST_F(RefereeTest, OverATouchLineTheOtherTeamThrowsIn) {
  Referee ref = referee();
  ASSERT_FALSE(ref.step(view({2, 5.0}, {2, 4.6}), Nanos{1s}, std::nullopt)) << "new touches it, in play";
  EXPECT_EQ(ref.last_touch(), 0u);
  const auto call = ref.step(view({2.5, 6.2}), Nanos{2s}, std::nullopt);
  ASSERT_TRUE(call);
  EXPECT_EQ(call->restart, Restart::kThrowIn);
  EXPECT_EQ(call->team, 1u);
  EXPECT_EQ(call->spot, Eigen::Vector2d(2.5, 6.0)) << "on the line where it left";
  EXPECT_EQ(ref.state_for(*call, 1), "our_throwin");
  EXPECT_FALSE(ref.step(view({2.5, 6.0}), Nanos{2s} + 100ms, std::nullopt)) << "taken, not called again";
}

TEST_F(RefereeTest, OverAGoalLineACornerOrAGoalKickByWhoTouchedLast) {
  Referee ref = referee();
  ref.step(view({8.5, 3}, {0, 0}, {8.5, 2.6}), Nanos{1s}, std::nullopt);  // old (defends +x) touches it
  auto call = ref.step(view({9.2, 4}), Nanos{2s}, std::nullopt);
  ASSERT_TRUE(call);
  EXPECT_EQ(call->restart, Restart::kCorner);
  EXPECT_EQ(call->team, 0u);
  EXPECT_EQ(call->spot, Eigen::Vector2d(9, 6));
  ASSERT_TRUE(ref.resume_due(Nanos{5s}));
  ref.step(view({8.5, -3}, {8.5, -2.6}), Nanos{6s}, std::nullopt);  // new (attacks +x) touches it
  call = ref.step(view({9.2, -4}), Nanos{7s}, std::nullopt);
  ASSERT_TRUE(call);
  EXPECT_EQ(call->restart, Restart::kGoalKick);
  EXPECT_EQ(call->team, 1u);
  EXPECT_EQ(call->spot, Eigen::Vector2d(9 - 0.75, -1.75)) << "the goal area's corner on its side";
}

TEST_F(RefereeTest, AStuckGameGetsADroppedBall) {
  RefereeRules rules;
  rules.stuck_s = 5;
  Referee ref = referee(rules);
  for (int s = 0; s < 5; ++s) {
    EXPECT_FALSE(ref.step(view({1, 1}, {-5, 0}, {5, 0}, 0.0), Nanos{std::chrono::seconds(s)}, std::nullopt));
  }
  const auto call = ref.step(view({1, 1}, {-5, 0}, {5, 0}, 0.0), Nanos{5s}, std::nullopt);
  ASSERT_TRUE(call);
  EXPECT_EQ(call->restart, Restart::kDroppedBall);
  EXPECT_FALSE(call->team);
  EXPECT_EQ(ref.state_for(*call, 0), "drop_ball");
  EXPECT_EQ(ref.state_for(*call, 1), "drop_ball");
}

TEST_F(RefereeTest, ABallPushedToAndFroOnOneSpotIsStuckTooOneThatTravelsIsNot) {
  RefereeRules rules;
  rules.stuck_s = 5;
  Referee jiggled = referee(rules);
  Referee rolling = referee(rules);
  std::optional<RefereeCall> a, b;
  for (int k = 0; k <= 60 && !a; ++k) {  // 0.1 s steps, the ball fast but within 0.3 m
    a = jiggled.step(view({1 + 0.3 * (k % 2), 1}, {-5, 0}, {5, 0}, 3.0), Nanos{k * 100ms}, std::nullopt);
  }
  ASSERT_TRUE(a);
  EXPECT_EQ(a->restart, Restart::kDroppedBall);
  EXPECT_EQ(a->time, Nanos{5s});
  for (int k = 0; k <= 60; ++k) {  // 0.1 m a step: 6 m in 6 s
    b = rolling.step(view({-3 + 0.1 * k, 1}, {-5, 0}, {5, 0}, 1.0), Nanos{k * 100ms}, std::nullopt);
    EXPECT_FALSE(b) << b->text;
  }
}

TEST_F(RefereeTest, RulesSwitchedOffCallNothingButGoalsStillCount) {
  RefereeRules rules;
  rules.kickoff_after_goal = false;
  rules.out_of_play = false;
  rules.dropped_ball = false;
  Referee ref = referee(rules);
  EXPECT_FALSE(ref.step(view({9.3, 0}), Nanos{1s}, true));
  EXPECT_EQ(ref.score(), (std::vector<int>{1, 0}));
  EXPECT_FALSE(ref.step(view({2, 6.5}), Nanos{2s}, std::nullopt));
  for (int s = 3; s < 40; ++s) {
    EXPECT_FALSE(ref.step(view({1, 1}, {-5, 0}, {5, 0}, 0.0), Nanos{std::chrono::seconds(s)}, std::nullopt));
  }
  EXPECT_TRUE(ref.calls().empty());
}

TEST_F(RefereeTest, AnUntouchedBallOutIsADrawTheSeedRepeats) {
  std::vector<std::size_t> takers;
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    Referee a = referee({}, seed);
    Referee b = referee({}, seed);
    const auto ca = a.step(view({0, 6.5}), Nanos{1s}, std::nullopt);
    const auto cb = b.step(view({0, 6.5}), Nanos{1s}, std::nullopt);
    ASSERT_TRUE(ca && cb && ca->team && cb->team);
    EXPECT_EQ(*ca->team, *cb->team) << "seed " << seed;
    takers.push_back(*ca->team);
  }
  EXPECT_NE(std::count(takers.begin(), takers.end(), 0u), 0) << "both teams win draws";
  EXPECT_NE(std::count(takers.begin(), takers.end(), 1u), 0);
}

TEST_F(RefereeTest, NoOutOfPlayCallWhileARestartIsTaken) {
  Referee ref = referee();
  ASSERT_TRUE(ref.step(view({0, 6.5}), Nanos{1s}, std::nullopt));
  EXPECT_FALSE(ref.step(view({0, 6.5}), Nanos{2s}, std::nullopt)) << "within the pause";
  EXPECT_TRUE(ref.resume_due(Nanos{3s}));
  EXPECT_TRUE(ref.step(view({0, 6.5}), Nanos{3s} + 10ms, std::nullopt)) << "after it";
}

TEST_F(RefereeTest, ABallIntoAGoalBeforeTheRestartIsTakenIsNoGoalTheRestartIsTakenAgain) {
  Referee ref = referee();
  ref.step(view({8.5, -3}, {8.5, -2.6}), Nanos{1s}, std::nullopt);  // new touches it
  const auto kick = ref.step(view({9.2, -4}), Nanos{2s}, std::nullopt);
  ASSERT_TRUE(kick);
  ASSERT_EQ(kick->restart, Restart::kGoalKick);
  EXPECT_FALSE(ref.ball_in_play());
  // 1.3 s into the pause a team that plays in every state but stop puts the ball into the goal.
  const auto again = ref.step(view({9.3, 0}), Nanos{3300ms}, true);
  ASSERT_TRUE(again) << "the goal kick again";
  EXPECT_EQ(ref.score(), (std::vector<int>{0, 0})) << "no goal";
  EXPECT_EQ(again->restart, Restart::kGoalKick);
  EXPECT_EQ(again->team, 1u);
  EXPECT_EQ(again->spot, kick->spot);
  EXPECT_FALSE(again->scorer);
  EXPECT_NE(again->text.find("before the goal kick was taken: no goal"), std::string::npos) << again->text;
  EXPECT_FALSE(ref.resume_due(Nanos{5s})) << "a new pause";
  // After "start": nudged in from the goal line, where it was left, it is still not in play.
  ref.step(view({8.95, 0.3}), Nanos{5300ms}, std::nullopt);
  ASSERT_TRUE(ref.resume_due(Nanos{5300ms}));
  EXPECT_FALSE(ref.ball_in_play()) << "not yet taken";
  EXPECT_FALSE(ref.ball_in_play_at({9.3, 0.3}));
  ASSERT_TRUE(ref.step(view({9.3, 0.3}), Nanos{5400ms}, true));
  EXPECT_EQ(ref.score(), (std::vector<int>{0, 0}));
  // Taken (moved 0.5 m after "start"): the ball is in play and a goal counts.
  ref.step(view({8.25, -1.75}), Nanos{7400ms}, std::nullopt);  // back on its spot
  ASSERT_TRUE(ref.resume_due(Nanos{7400ms}));
  EXPECT_FALSE(ref.step(view({7.7, -1.6}), Nanos{7500ms}, std::nullopt));
  EXPECT_TRUE(ref.ball_in_play());
  const auto goal = ref.step(view({9.3, 0}), Nanos{8s}, true);
  ASSERT_TRUE(goal);
  EXPECT_EQ(goal->restart, Restart::kKickoff);
  EXPECT_EQ(ref.score(), (std::vector<int>{1, 0}));
}

}  // namespace
}  // namespace canhil::emulator
