// Physical invariants of the world, with tolerances; no recorded trajectories.
#include "canhil/physics/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "canhil/kinematics/omni.hpp"

namespace canhil::physics {
namespace {

constexpr double kPi = std::numbers::pi;

WorldParams one_robot() {
  WorldParams p;
  p.robots = {Placement{0, 0, 0}};  // front (+y of the robot) along world +y
  p.ball_start = {3, 3, p.ball.radius_m};
  return p;
}

void run(World& w, double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / w.params().simulation.step_s));
  for (int i = 0; i < steps; ++i) w.step();
}

TEST(Ball, DroppedBallLosesEnergyAtEveryBounceAndComesToRest) {
  WorldParams p;
  p.ball_start = {0, 0, 1.0 + p.ball.radius_m};
  World w(p);
  std::vector<double> apexes;
  double apex = 0;
  double last_vz = 0;
  const double r = p.ball.radius_m;
  while (w.time_s() < 5.0) {
    w.step();
    const double vz = w.ball_velocity().z();
    apex = std::max(apex, w.ball_position().z() - r);
    if (last_vz < -0.01 && vz >= -0.01) {
      apexes.push_back(apex);
      apex = 0;
    }
    last_vz = vz;
  }
  ASSERT_GE(apexes.size(), 6u);
  for (std::size_t i = 1; i < apexes.size(); ++i) {
    EXPECT_LT(apexes[i], apexes[i - 1]) << "bounce " << i << " gained height";
  }
  EXPECT_NEAR(w.ball_position().z(), r, 0.002) << "at rest on the carpet";
  EXPECT_LT(w.ball_velocity().norm(), 0.01);
}

TEST(Ball, FlightIsUntouchedByRollingResistance) {
  WorldParams p;
  World w(p);
  w.place_ball({0, 0, 5.0}, {4.0, -1.5, 3.0});
  run(w, 0.8);  // still in the air
  ASSERT_GT(w.ball_position().z(), 1.0);
  EXPECT_EQ(w.ball_velocity().x(), 4.0) << "no damping of a ball in flight";
  EXPECT_EQ(w.ball_velocity().y(), -1.5);
  EXPECT_NEAR(w.ball_velocity().z(), 3.0 - p.simulation.gravity_mps2 * 0.8, 1e-9);
}

TEST(Ball, RollingBallComesToAFullStop) {
  WorldParams p;
  World w(p);
  const double r = p.ball.radius_m;
  w.place_ball({-5, 0, r}, {2.0, 0, 0}, {0, 2.0 / r, 0});
  run(w, 1.0);
  EXPECT_GT(w.ball_velocity().norm(), 1.0) << "still rolling after 1 s";
  EXPECT_TRUE(w.ball_on_ground());
  run(w, 10.0);
  EXPECT_LT(w.ball_velocity().norm(), 1e-3) << "stopped";
  const double expected = 2.0 * 2.0 / (2 * p.ball.rolling_resistance * p.simulation.gravity_mps2);
  EXPECT_NEAR(w.ball_position().x() + 5, expected, 0.05 * expected);
}

class Barrier : public ::testing::Test {
 protected:
  Barrier() : w_(one_robot()) {}
  // Ball centre at `distance` from the robot centre, `bearing_deg` off its
  // front (positive to the left), centre `height` above the carpet.
  bool engaged_at(double distance, double bearing_deg, double height) {
    const double a = kPi / 2 + bearing_deg * kPi / 180.0;  // front is world +y
    w_.place_ball({distance * std::cos(a), distance * std::sin(a), height});
    return w_.robot(0).ball_engaged();
  }
  World w_;
  const BarrierParams& b_ = w_.params().robot.barrier;
  const double r_ = w_.params().ball.radius_m;
};

TEST_F(Barrier, DistanceBoundaryBothSides) {
  EXPECT_TRUE(engaged_at(b_.max_distance_m - 1e-3, 0, r_));
  EXPECT_FALSE(engaged_at(b_.max_distance_m + 1e-3, 0, r_));
}

TEST_F(Barrier, AngleBoundaryBothSidesLeftAndRight) {
  for (const double side : {-1.0, 1.0}) {
    EXPECT_TRUE(engaged_at(0.27, side * (b_.half_angle_deg - 0.2), r_)) << side;
    EXPECT_FALSE(engaged_at(0.27, side * (b_.half_angle_deg + 0.2), r_)) << side;
  }
  EXPECT_FALSE(engaged_at(0.27, 180, r_)) << "behind the robot";
}

TEST_F(Barrier, HeightBoundaryBothSides) {
  EXPECT_TRUE(engaged_at(0.27, 0, b_.max_height_m - 1e-3));
  EXPECT_FALSE(engaged_at(0.27, 0, b_.max_height_m + 1e-3));
}

TEST(Kicker, DoesNothingWhenTheBallIsNotEngaged) {
  World w(one_robot());
  w.place_ball({0, 1.0, w.params().ball.radius_m});
  run(w, 0.2);
  const Eigen::Vector3d before = w.ball_velocity();
  const double volts = w.robot(0).kicker_voltage_v();
  const KickResult k = w.robot(0).kick(true, 50);
  EXPECT_EQ(k.outcome, KickOutcome::kNotEngaged);
  EXPECT_EQ(w.ball_velocity(), before);
  EXPECT_EQ(w.robot(0).kicker_voltage_v(), volts);
  EXPECT_LT(w.robot(0).last_kick_time_s(), 0);
}

WorldParams robot_holding_ball() {
  WorldParams p = one_robot();
  const RobotParams& rp = p.robot;
  p.ball_start = {0, rp.body_radius_m - rp.mouth_depth_m + p.ball.radius_m, p.ball.radius_m};
  return p;
}

TEST(Kicker, FiresWhenEngagedDrainsTheCapacitorAndRecharges) {
  World w(robot_holding_ball());
  Robot& robot = w.robot(0);
  robot.set_grabber(100);
  run(w, 0.3);
  ASSERT_TRUE(robot.ball_engaged());
  const double full = robot.kicker_voltage_v();
  const KickResult k = robot.kick(true, 50);
  ASSERT_TRUE(k.fired());
  EXPECT_GT(w.ball_velocity().y(), 0.9 * k.speed_mps) << "launched forward";
  const double after = robot.kicker_voltage_v();
  EXPECT_LT(after, 0.7 * full);
  run(w, 0.5);
  EXPECT_GT(robot.kicker_voltage_v(), after) << "recharging";
  EXPECT_GT(w.ball_position().y(), 1.5) << "the grabber let go: the ball left";
  run(w, 10.0);
  EXPECT_NEAR(robot.kicker_voltage_v(), full, 0.01 * full);
}

TEST(Kicker, RefusesBelowTheFiringVoltageAndCapsPower) {
  WorldParams p = robot_holding_ball();
  p.robot.kicker.energy_per_full_kick = 0.99;
  p.robot.kicker.recharge_time_constant_s = 1000;
  World w(p);
  Robot& robot = w.robot(0);
  robot.set_grabber(100);
  run(w, 0.3);
  const KickResult first = robot.kick(true, 127);  // capped to 50
  ASSERT_TRUE(first.fired());
  const double g = p.simulation.gravity_mps2;
  const double v_max = std::sqrt(p.robot.kicker.max_lob_range_m * g / std::sin(2 * 45.0 * kPi / 180));
  EXPECT_NEAR(first.speed_mps, v_max, 1e-9);
  w.place_ball({0, 0.26, p.ball.radius_m});
  run(w, 0.3);
  ASSERT_TRUE(robot.ball_engaged());
  EXPECT_EQ(robot.kick(false, 50).outcome, KickOutcome::kLowVoltage);
}

TEST(Grabber, PullsTheBallIntoTheControlAreaOnlyWhenOn) {
  for (const int mode : {0, 100}) {
    WorldParams p = one_robot();
    p.ball_start = {0, 0.42, p.ball.radius_m};
    World w(p);
    ASSERT_FALSE(w.robot(0).ball_engaged());
    w.robot(0).set_grabber(mode);
    w.robot(0).brake();
    run(w, 1.5);
    EXPECT_EQ(w.robot(0).ball_engaged(), mode > 0) << "mode " << mode;
  }
}

TEST(Encoders, CountsFollowTheWheelAngle) {
  World w(one_robot());
  Robot& robot = w.robot(0);
  const kinematics::EncoderSpec& e = robot.params().encoder;
  for (int n = 0; n < 3; ++n) robot.set_wheel_speed(n, 2 * kPi);  // one wheel turn per second: spins in place
  run(w, 1.0);
  for (int n = 0; n < 3; ++n) {
    EXPECT_EQ(robot.encoder_count(n), static_cast<std::int64_t>(std::floor(e.counts(robot.wheel_angle_rad(n)))));
    EXPECT_NEAR(static_cast<double>(robot.encoder_count(n)), e.counts_per_wheel_rev(), 0.03 * e.counts_per_wheel_rev());
  }
  EXPECT_GT(std::fabs(robot.pose().heading_rad), 0.5) << "equal wheel speeds turn the robot";
}

TEST(Compass, HeadingFromYawWithNorthOffset) {
  WorldParams p = one_robot();
  p.robot.compass.north_offset_deg = 90;  // north is world +y: the robot's front at start
  World w(p);
  EXPECT_NEAR(w.robot(0).compass_heading_deg(), 0.0, 1e-6);
  w.robot(0).place(Placement{0, 0, 10});  // turned 10 deg counter-clockwise
  EXPECT_NEAR(w.robot(0).compass_heading_deg(), 350.0, 1e-6);
  w.robot(0).place(Placement{0, 0, -90});  // front along world +x: east
  EXPECT_NEAR(w.robot(0).compass_heading_deg(), 90.0, 1e-6);
}

TEST(Battery, SagsUnderMotorCurrentAndDrains) {
  World w(one_robot());
  Robot& robot = w.robot(0);
  run(w, 0.2);
  const BatteryVolts idle = robot.battery();
  EXPECT_NEAR(idle.power24_v, 25.2 - 0.3 * 0.08, 0.01);
  for (int n = 0; n < 3; ++n) robot.set_wheel_speed(n, 40.0);  // hard acceleration
  w.step();
  w.step();
  EXPECT_LT(robot.battery().power24_v, idle.power24_v - 1.0) << "30 A through 80 mOhm";
  EXPECT_TRUE(robot.over_current(0));
  run(w, 5.0);
  robot.brake();
  run(w, 1.0);
  EXPECT_LT(robot.battery().power24_v, idle.power24_v) << "charge used";
  EXPECT_LT(robot.battery().logic_v, idle.logic_v);
}

TEST(Motors, StalledWheelIsReported) {
  WorldParams p = one_robot();
  ObstaclePlacement wall;
  wall.at = Placement{0, 0.55, 0};
  wall.params.radius_m = 0.3;
  p.obstacles = {wall};
  World w(p);
  const kinematics::OmniKinematics k(p.robot.geometry);
  const auto ws = k.inverse({0, 1.0, 0});  // drive into the static obstacle
  for (int n = 0; n < 3; ++n) w.robot(0).set_wheel_speed(n, ws[static_cast<std::size_t>(n)]);
  run(w, 2.0);
  EXPECT_TRUE(w.robot(0).wheel_stalled(0) || w.robot(0).wheel_stalled(1));
  EXPECT_FALSE(w.robot(0).wheel_stalled(2)) << "wheel 3 is not commanded when driving forward";
}

TEST(Obstacles, MovableOnesArePushedStaticOnesNever) {
  for (const bool movable : {false, true}) {
    WorldParams p = one_robot();
    ObstaclePlacement o;
    o.at = Placement{0, 0.8, 0};
    o.params.movable = movable;
    p.obstacles = {o};
    World w(p);
    run(w, 0.5);  // a movable obstacle falls asleep at rest
    const Eigen::Vector3d start = w.obstacle_position(0);
    const kinematics::OmniKinematics k(p.robot.geometry);
    const auto ws = k.inverse({0, 1.0, 0});
    for (int n = 0; n < 3; ++n) w.robot(0).set_wheel_speed(n, ws[static_cast<std::size_t>(n)]);
    run(w, 2.0);
    const double moved = (w.obstacle_position(0) - start).norm();
    if (movable) {
      EXPECT_GT(moved, 0.3) << "pushed (and woken up from sleep)";
    } else {
      EXPECT_EQ(moved, 0.0);
      // Obstacle surface at 0.55; the robot's front is 0.25 ahead of its centre
      // with a 0.10 deep mouth the obstacle can enter.
      EXPECT_LT(w.robot(0).pose().y_m, 0.45) << "the robot is stopped by a static obstacle";
    }
  }
}

WorldParams busy_scene() {
  WorldParams p;
  for (int i = 0; i < 3; ++i) p.robots.push_back(Placement{-2.0 + 2.0 * i, -1.0, 30.0 * i});
  for (int i = 0; i < 2; ++i) {
    ObstaclePlacement o;
    o.at = Placement{-1.0 + 2.0 * i, 0.8, 0};
    o.params.movable = i == 1;
    p.obstacles.push_back(o);
  }
  p.ball_start = {0, 0, 0.5};
  return p;
}

void drive_all(World& w, double t) {
  const kinematics::OmniKinematics k(w.params().robot.geometry);
  for (std::size_t r = 0; r < w.robot_count(); ++r) {
    const auto ws = k.inverse({0.5 * std::sin(t + static_cast<double>(r)), 0.8, 0.7});
    for (int n = 0; n < 3; ++n) w.robot(r).set_wheel_speed(n, ws[static_cast<std::size_t>(n)]);
    w.robot(r).set_grabber(50);
  }
}

TEST(SaveRestore, SaveStepRestoreStepIsBitIdentical) {
  World w(busy_scene());
  w.place_ball({0, 0, 0.5}, {1.0, 0.5, 2.0});
  for (int i = 0; i < 100; ++i) {
    drive_all(w, w.time_s());
    w.step();
  }
  const WorldState saved = w.save();
  for (int i = 0; i < 150; ++i) {
    drive_all(w, w.time_s());
    w.step();
  }
  const WorldState first = w.save();
  w.restore(saved);
  EXPECT_EQ(w.save(), saved) << "restore reproduces the saved state exactly";
  for (int i = 0; i < 150; ++i) {
    drive_all(w, w.time_s());
    w.step();
  }
  const WorldState second = w.save();
  EXPECT_TRUE(first == second) << "stepping from a restored state repeats the original bit for bit";
  EXPECT_NE(first, saved);
}

TEST(SaveRestore, FileRoundTripIsExactAndRestores) {
  World w(busy_scene());
  for (int i = 0; i < 60; ++i) {
    drive_all(w, w.time_s());
    w.step();
  }
  const WorldState saved = w.save();
  const auto path = std::filesystem::temp_directory_path() / "canhil_world_state_test.txt";
  save_state(saved, path);
  const WorldState loaded = load_state(path);
  EXPECT_EQ(loaded, saved);
  World other(busy_scene());
  other.restore(loaded);
  for (int i = 0; i < 50; ++i) {
    drive_all(w, w.time_s());
    w.step();
    drive_all(other, other.time_s());
    other.step();
  }
  EXPECT_EQ(other.save(), w.save()) << "a second world restored from the file runs identically";
  std::filesystem::remove(path);
}

TEST(SaveRestore, RefusesAStateOfAnotherWorldAndMalformedFiles) {
  World w(busy_scene());
  World small(one_robot());
  EXPECT_THROW(small.restore(w.save()), SetupError);
  const auto path = std::filesystem::temp_directory_path() / "canhil_bad_state.txt";
  {
    std::ofstream out(path);
    out << "canhil-world-state 1\ntime 0x0p+0\nseed 1\nball 1 2 3\n";
  }
  try {
    load_state(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":4: world state has too few numbers"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(World, RefusesStartPositionsInsideEachOther) {
  WorldParams p;
  p.robots = {Placement{0, 0, 0}};
  p.ball_start = {0.1, 0, 0.11};
  EXPECT_THROW(World{p}, SetupError) << "ball inside a robot";
  p.ball_start = {0.5, 0, 0.11};
  EXPECT_NO_THROW(World{p});
  p.ball_start = {0, 0.26, 0.11};  // held in the mouth (the front is +y at heading 0)
  EXPECT_NO_THROW(World{p});
  p.ball_start = {0, -0.26, 0.11};  // the same distance behind: inside the body
  EXPECT_THROW(World{p}, SetupError);
  p.ball_start = {0.5, 0, 0.11};
  p.robots.push_back(Placement{0.3, 0.2, 0});
  try {
    World w(p);
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("robot 0 and robot 1 start overlapping"), std::string::npos) << e.what();
  }
}

TEST(Robot, PlaceTeleportsAndStops) {
  World w(one_robot());
  w.robot(0).place(Placement{2.0, -1.0, 45});
  const kinematics::Pose pose = w.robot(0).pose();
  EXPECT_NEAR(pose.x_m, 2.0, 1e-12);
  EXPECT_NEAR(pose.y_m, -1.0, 1e-12);
  EXPECT_NEAR(pose.heading_rad, kPi / 4, 1e-12);
  w.robot(0).brake();
  run(w, 0.5);
  EXPECT_NEAR(w.robot(0).pose().x_m, 2.0, 1e-3) << "stands still on its wheels";
  EXPECT_NEAR(w.robot(0).twist().vy_mps, 0.0, 1e-3);
}

// Three robots driving into the ball at the centre from three sides (a scrum:
// one island of well over 64 rows), and a fourth robot alone at (5, 3)
// turning on the spot.
WorldParams scrum_scene(int exact_solver_max_rows) {
  WorldParams p;
  for (int i = 0; i < 3; ++i) {
    const double a = 2 * kPi * i / 3;
    // Heading so that the robot's front (+y) points at the centre.
    p.robots.push_back(Placement{0.6 * std::cos(a), 0.6 * std::sin(a), a * 180 / kPi + 90});
  }
  p.robots.push_back(Placement{5, 3, 0});
  p.ball_start = {0, 0, p.ball.radius_m};
  p.simulation.exact_solver_max_rows = exact_solver_max_rows;
  return p;
}

void push_in(World& w) {
  const kinematics::OmniKinematics k(w.params().robot.geometry);
  const auto ahead = k.inverse({0, 1.0, 0});
  for (std::size_t r = 0; r < 3; ++r) {
    for (int n = 0; n < 3; ++n) w.robot(r).set_wheel_speed(n, ahead[static_cast<std::size_t>(n)]);
  }
  const auto turn = k.inverse({0, 0, 2.0});
  for (int n = 0; n < 3; ++n) w.robot(3).set_wheel_speed(n, turn[static_cast<std::size_t>(n)]);
}

TEST(Scrum, RobotsPushingTogetherMakeMoreContactPointsThanStandingApart) {
  World pushing(scrum_scene(64));
  World standing(scrum_scene(64));
  EXPECT_EQ(pushing.contact_points(), 0U) << "none before the first step";
  for (int i = 0; i < 300; ++i) {
    push_in(pushing);
    pushing.step();
    standing.step();
  }
  // Four robots on three wheels each, in every substep, at the least.
  const auto substeps = static_cast<std::uint64_t>(standing.params().simulation.substeps);
  EXPECT_GE(standing.contact_points(), 300 * substeps * 4 * 3);
  EXPECT_GT(pushing.contact_points(), standing.contact_points() + 300 * substeps)
      << "the three robots pushing into one another touch, each substep";
}

TEST(Scrum, ALargeIslandGoesToQuickStepAndStaysTogether) {
  World w(scrum_scene(64));
  for (int i = 0; i < 300; ++i) {
    push_in(w);
    w.step();
  }
  EXPECT_GT(w.large_island_substeps(), 200u) << "the three robots pushing together are one large island";
  const double r = w.params().robot.body_radius_m;
  for (std::size_t a = 0; a < 3; ++a) {
    const kinematics::Pose pa = w.robot(a).pose();
    EXPECT_LT(std::hypot(pa.x_m, pa.y_m), 1.0) << "robot " << a << " stays in the scrum, not thrown out";
    const kinematics::Twist v = w.robot(a).twist();
    EXPECT_LT(std::hypot(v.vx_mps, v.vy_mps), 0.5) << "robot " << a << " pushes, it does not fly";
    EXPECT_NEAR(w.save().robots[a].chassis.position[2], w.save().robots[3].chassis.position[2], 0.02)
        << "robot " << a << " on its wheels";
    for (std::size_t b = a + 1; b < 3; ++b) {
      const kinematics::Pose pb = w.robot(b).pose();
      EXPECT_GT(std::hypot(pa.x_m - pb.x_m, pa.y_m - pb.y_m), 2 * r - 0.12) << "robots " << a << " and " << b;
    }
  }
  World exact(scrum_scene(0));
  for (int i = 0; i < 10; ++i) {
    push_in(exact);
    exact.step();
  }
  EXPECT_EQ(exact.large_island_substeps(), 0u) << "0: every island exactly";
}

TEST(Scrum, SmallIslandsKeepTheExactSolverBitForBit) {
  World split(scrum_scene(64));
  World exact(scrum_scene(0));
  for (int i = 0; i < 300; ++i) {
    push_in(split);
    push_in(exact);
    split.step();
    exact.step();
  }
  ASSERT_GT(split.large_island_substeps(), 0u);
  const WorldState a = split.save();
  const WorldState b = exact.save();
  EXPECT_TRUE(a.robots[3] == b.robots[3]) << "the lone robot's island is stepped exactly either way";
  EXPECT_FALSE(a.robots[0] == b.robots[0]) << "the scrum is stepped differently";
}

TEST(Scrum, SplitStepsRepeatAndRestoreBitForBit) {
  World w(scrum_scene(64));
  for (int i = 0; i < 100; ++i) {
    push_in(w);
    w.step();
  }
  const WorldState saved = w.save();
  for (int i = 0; i < 100; ++i) {
    push_in(w);
    w.step();
  }
  const WorldState first = w.save();
  World other(scrum_scene(64));
  other.restore(saved);
  for (int i = 0; i < 100; ++i) {
    push_in(other);
    other.step();
  }
  EXPECT_TRUE(other.save() == first) << "QuickStep's shuffling seed is part of the state";
}

}  // namespace
}  // namespace canhil::physics
