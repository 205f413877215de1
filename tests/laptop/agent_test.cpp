#include "canhil/laptop/agent.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace canhil::laptop {
namespace {

TEST(Agent, SearchesWhenNoBallIsSeen) {
  Agent a;
  const AgentOutput out = a.decide(AgentInput{});
  EXPECT_EQ(a.state(), AgentState::kSearch);
  EXPECT_GT(out.va_radps, 0);
  EXPECT_EQ(out.vx_mps, 0);
  EXPECT_EQ(out.kick, 0);
}

TEST(Agent, DrivesToTheBallFacingItWithTheGrabberOnWhenNear) {
  Agent a;
  AgentInput in;
  in.ball_seen = true;
  in.ball_x_m = 0.0;
  in.ball_y_m = 2.0;  // straight ahead
  AgentOutput out = a.decide(in);
  EXPECT_EQ(a.state(), AgentState::kApproach);
  EXPECT_GT(out.vy_mps, 1.0);
  EXPECT_NEAR(out.vx_mps, 0, 1e-9);
  EXPECT_NEAR(out.va_radps, 0, 1e-9);
  EXPECT_EQ(out.grabber, 0) << "far: grabber off";
  in.ball_x_m = 0.5;  // ahead and to the right
  in.ball_y_m = 0.5;
  out = a.decide(in);
  EXPECT_LT(out.va_radps, 0) << "turns right (clockwise) towards it";
  EXPECT_GT(out.vx_mps, 0);
  EXPECT_EQ(out.grabber, 100);
}

TEST(Agent, AimsAtTheGoalAndKicksOnceThenCoolsDown) {
  AgentConfig cfg;
  cfg.goal_x_m = 9;
  Agent a(cfg);
  AgentInput in;
  in.ball_engaged = true;
  in.x_m = 0;
  in.y_m = 0;
  in.heading_rad = 0;  // front along world +y: the goal (+x) is 90 deg to the right
  AgentOutput out = a.decide(in);
  EXPECT_EQ(a.state(), AgentState::kAim);
  EXPECT_LT(out.va_radps, 0) << "turn right towards the goal";
  EXPECT_EQ(out.kick, 0);
  in.heading_rad = -std::numbers::pi / 2;  // now the front points at the goal
  int kicks = 0;
  for (int i = 0; i < 10; ++i) {
    out = a.decide(in);
    if (out.kick != 0) {
      ++kicks;
      EXPECT_EQ(out.kick, 0x80 | 40) << "low kick at the configured power";
    }
  }
  EXPECT_EQ(kicks, 1) << "one kick, then the cooldown";
  EXPECT_EQ(a.state(), AgentState::kCooldown);
  in.dt_s = 1.5;
  in.ball_engaged = false;
  a.decide(in);
  EXPECT_EQ(a.state(), AgentState::kSearch);
}

TEST(Agent, StandsStillWhileTheCoachDoesNotSayStart) {
  Agent a;
  AgentInput in;
  in.ball_engaged = true;
  in.heading_rad = -std::numbers::pi / 2;  // aimed at the goal: it would kick
  in.play = false;
  for (int i = 0; i < 10; ++i) {
    const AgentOutput out = a.decide(in);
    EXPECT_EQ(out.vx_mps, 0);
    EXPECT_EQ(out.vy_mps, 0);
    EXPECT_EQ(out.va_radps, 0);
    EXPECT_EQ(out.grabber, 0);
    EXPECT_EQ(out.kick, 0) << "no kick before the restart";
  }
  EXPECT_EQ(a.kicks(), 0);
  in.play = true;
  int kicks = 0;
  for (int i = 0; i < 10; ++i) kicks += a.decide(in).kick != 0 ? 1 : 0;
  EXPECT_EQ(kicks, 1) << "on start it aims afresh, then kicks";
}

TEST(Agent, AfterTheOtherTeamsRestartItKeepsOffTheBallUntilItMoves) {
  Agent a;
  AgentInput in;
  in.play = false;
  in.their_restart = true;  // "their_kickoff": the other team kicks off
  in.ball_seen = true;
  in.ball_y_m = 2.0;  // straight ahead, 2 m
  a.decide(in);
  in.play = true;  // "start"
  in.their_restart = false;
  for (int i = 0; i < 10; ++i) {
    const AgentOutput out = a.decide(in);
    EXPECT_EQ(a.state(), AgentState::kWait);
    EXPECT_EQ(out.vx_mps, 0);
    EXPECT_EQ(out.vy_mps, 0);
    EXPECT_EQ(out.grabber, 0);
  }
  in.ball_y_m = 1.4;  // played: 0.6 m towards it
  const AgentOutput out = a.decide(in);
  EXPECT_EQ(a.state(), AgentState::kApproach);
  EXPECT_GT(out.vy_mps, 0.5);
}

TEST(Agent, ARestartTheOtherTeamLeavesIsInPlayAfterTheWait) {
  AgentConfig cfg;
  cfg.restart_wait_s = 2.0;
  Agent a(cfg);
  AgentInput in;
  in.play = false;
  in.their_restart = true;
  in.ball_seen = true;
  in.ball_y_m = 2.0;
  a.decide(in);
  in.play = true;
  in.their_restart = false;
  in.dt_s = 0.5;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.decide(in).vy_mps, 0) << "waiting, " << 0.5 * (i + 1) << " s";
  EXPECT_GT(a.decide(in).vy_mps, 0.5) << "2 s: it plays";
}

TEST(Agent, AfterItsOwnRestartOrADroppedBallItPlaysAtOnce) {
  Agent a;
  AgentInput in;
  in.play = false;  // "our_goalkick", "drop_ball", "stop": not the other team's
  in.ball_seen = true;
  in.ball_y_m = 2.0;
  a.decide(in);
  in.play = true;
  EXPECT_GT(a.decide(in).vy_mps, 0.5);
  EXPECT_EQ(a.state(), AgentState::kApproach);
}

}  // namespace
}  // namespace canhil::laptop
