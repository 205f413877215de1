// A running world saved as a scenario reads back as the same scenario, placed
// where the world had things; the tables it does not write are kept.
#include "canhil/emulator/scenario_writer.hpp"

#include <gtest/gtest.h>

#include "canhil/base/setup_error.hpp"

namespace canhil::emulator {
namespace {

TEST(ScenarioWriter, ASavedWorldReadsBackWithItsPlacementsAndEverythingElse) {
  const Scenario original = parse_scenario(R"(
[run]
duration_s = 7
seed = 42
kick_power = 30
interfaces = ["can0", "can1"]
agents = [3, 5]
faults = ["drop:M4_1:0.1"]

[coach]
game_state = "stop"
roles = ["goalie", "striker"]

[ball]
radius_m = 0.12

[[robots]]
x_m = -1.0
y_m = 0.0

[[robots]]
x_m = 1.0
y_m = 1.0

[[obstacles]]
x_m = 2.0
y_m = 2.0
radius_m = 0.3
movable = true
)",
                                           "original.toml");
  WorldSnapshot now;
  now.robots = {kinematics::Pose{4.25, -2.5, 0.5}, kinematics::Pose{-1.0, 3.0, -1.5707963}};
  now.obstacles = {Eigen::Vector3d(-3, 1, 0.35)};
  now.ball = Eigen::Vector3d(0.5, -0.25, 0.12);
  now.coach = original.coach;
  now.coach.game_state = "our_kickoff";
  const Scenario back = parse_scenario(scenario_toml(original, now), "saved.toml");
  EXPECT_EQ(back.duration_s, 7);
  EXPECT_EQ(back.seed, 42u);
  EXPECT_EQ(back.kick_power, 30);
  EXPECT_EQ(back.interfaces, original.interfaces);
  EXPECT_EQ(back.agents, original.agents);
  ASSERT_EQ(back.faults.size(), 1u);
  EXPECT_EQ(back.faults[0].text, "drop:M4_1:0.1");
  EXPECT_EQ(back.coach.game_state, "our_kickoff");
  EXPECT_EQ(back.coach.players[0].role, "goalie");
  EXPECT_EQ(back.world.ball.radius_m, 0.12);  // a physics table kept
  ASSERT_EQ(back.world.robots.size(), 2u);
  EXPECT_NEAR(back.world.robots[0].x_m, 4.25, 1e-9);
  EXPECT_NEAR(back.world.robots[0].heading_deg, 28.65, 0.01);
  EXPECT_NEAR(back.world.robots[1].heading_deg, -90, 0.01);
  ASSERT_EQ(back.world.obstacles.size(), 1u);
  EXPECT_EQ(back.world.obstacles[0].at.x_m, -3);
  EXPECT_EQ(back.world.obstacles[0].params.radius_m, 0.3);
  EXPECT_TRUE(back.world.obstacles[0].params.movable);
  EXPECT_NEAR(back.world.ball_start.x_m, 0.5, 1e-9);
  EXPECT_NEAR(back.world.ball_start.z_m, 0.12, 1e-9);
}

TEST(ScenarioWriter, AScenarioBuiltInCodeSavesToo) {
  Scenario sc;
  complete(sc);
  WorldSnapshot now;
  now.robots = {kinematics::Pose{0, 0, 0}};
  now.ball = Eigen::Vector3d(0, 0, 0.11);
  now.coach = sc.coach;
  const Scenario back = parse_scenario(scenario_toml(sc, now), "saved.toml");
  EXPECT_EQ(back.world.robots.size(), 1u);
  EXPECT_EQ(back.world.field, sc.world.field);
}

}  // namespace
}  // namespace canhil::emulator
