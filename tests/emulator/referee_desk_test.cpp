// The referee's calls carried out in the world: at a throw-in the robots
// nearer than [referee] restart_distance_m to the spot step back that far
// towards their own goal (the distance a team can set), the others stay; at
// a kick-off every robot goes back to its place.
#include "canhil/emulator/referee_desk.hpp"

#include <gtest/gtest.h>

#include "canhil/physics/world.hpp"
#include "support/counter_watch.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class RefereeDeskTest : public test::WatchedTest {
 protected:
  // The shipped two-team scenario, every robot parked far from (0, 3) but robot 0,
  // which stands `from_spot` metres below the touch line's centre.
  static Scenario scenario(double restart_distance_m) {
    Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
    s.referee.enabled = true;
    s.referee.restart_distance_m = restart_distance_m;
    return s;
  }
  static void park(physics::World& world, double from_spot) {
    const double half_width = world.params().field.width_m / 2;
    for (std::size_t r = 1; r < world.robot_count(); ++r) {
      world.robot(r).place({-7.0 + 1.2 * static_cast<double>(r), -half_width + 1.0, 90});
    }
    world.robot(0).place({0.0, half_width - from_spot, 90});
  }
  // The ball wholly over the +y touch line at x = 0, as if robot 0 had played it there.
  static RefereeDesk::Outcome throw_in(RefereeDesk& desk, physics::World& world) {
    const double half_width = world.params().field.width_m / 2;
    world.place_ball({0.0, half_width + 0.5, 0.11}, Eigen::Vector3d::Zero());
    return desk.step(world, Nanos{1s}, std::nullopt);
  }
  static double from_spot(const physics::World& world, std::size_t r) {
    const kinematics::Pose p = world.robot(r).pose();
    return std::hypot(p.x_m, p.y_m - world.params().field.width_m / 2);
  }
};

TEST_F(RefereeDeskTest, ARobotNearerThanTheRestartDistanceStepsBackThatFar) {
  const Scenario s = scenario(2.0);
  physics::World world(s.world);
  park(world, 1.5);
  RefereeDesk desk(s);
  const auto out = throw_in(desk, world);
  ASSERT_TRUE(out.call);
  EXPECT_EQ(out.call->restart, Restart::kThrowIn);
  EXPECT_GE(from_spot(world, 0), 2.0);
  EXPECT_EQ(desk.placements(0), 1u);
  const double own = s.teams[s.team_of(0)].attacks_positive_x ? -1.0 : 1.0;
  EXPECT_GT(world.robot(0).pose().x_m * own, 0) << "towards its own goal";
  for (std::size_t r = 1; r < s.robot_count(); ++r) EXPECT_EQ(desk.placements(r), 0u) << "robot " << r;
}

TEST_F(RefereeDeskTest, ARobotAsFarAsTheRestartDistanceStays) {
  const Scenario s = scenario(1.0);
  physics::World world(s.world);
  park(world, 1.5);
  RefereeDesk desk(s);
  const auto out = throw_in(desk, world);
  ASSERT_TRUE(out.call);
  EXPECT_NEAR(from_spot(world, 0), 1.5, 1e-9);
  EXPECT_EQ(desk.placements(0), 0u);
}

TEST_F(RefereeDeskTest, AtAKickOffEveryRobotGoesBackToItsPlace) {
  const Scenario s = scenario(1.0);
  physics::World world(s.world);
  park(world, 1.5);
  RefereeDesk desk(s);
  world.place_ball({s.world.field.length_m / 2 + 0.3, 0.0, 0.11}, Eigen::Vector3d::Zero());
  const auto out = desk.step(world, Nanos{1s}, true);
  ASSERT_TRUE(out.call);
  EXPECT_EQ(out.call->restart, Restart::kKickoff);
  for (std::size_t r = 0; r < s.robot_count(); ++r) {
    EXPECT_NEAR(world.robot(r).pose().x_m, s.world.robots[r].x_m, 1e-9) << "robot " << r;
    EXPECT_EQ(desk.placements(r), 1u);
  }
  EXPECT_NEAR(world.ball_position().x(), 0.0, 1e-9) << "the ball to the centre";
}

}  // namespace
}  // namespace canhil::emulator
