// Emulated vision, noise off: geometry checked exactly.
#include "canhil/vision_emu/vision.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "canhil/vision_emu/runner.hpp"

namespace canhil::vision_emu {
namespace {

constexpr double kPi = std::numbers::pi;

class VisionTest : public ::testing::Test {
 protected:
  VisionTest() : vision_(VisionParams{}, physics::field_markings(physics::FieldParams{})) {}
  Scene scene_with(kinematics::Pose me) {
    Scene s;
    s.robots = {me};
    s.ball = {50, 50, 0.11};  // far away unless a test places it
    return s;
  }
  VisionFrame see(const Scene& s, std::size_t robot = 0) {
    NoiseEngine rng(1);
    return vision_.see(s, robot, rng);
  }
  Vision vision_;
};

TEST_F(VisionTest, EveryLinePointLiesOnAMarking) {
  for (const kinematics::Pose& me :
       {kinematics::Pose{-3, 0, 0.3}, kinematics::Pose{6, 4, -1.2}, kinematics::Pose{0.5, -2, 2.0}}) {
    const VisionFrame f = see(scene_with(me));
    ASSERT_GT(f.lines.size(), 20u);
    for (const auto& p : f.lines) {
      const Eigen::Vector2d w = Vision::to_world(me, p);
      EXPECT_LE(vision_.markings().distance_to_nearest(w.x(), w.y()), 1e-3) << "(" << w.x() << ", " << w.y() << ")";
      EXPECT_LE(p.norm(), vision_.params().line_range_m + 1e-9);
    }
  }
}

TEST_F(VisionTest, ObstaclePointsLieOnTheNearestObstacleAlongTheirRay) {
  Scene s = scene_with({0, 0, 0});
  s.obstacles = {{{2.0, 0.0}, 0.25}, {{3.5, 0.3}, 0.4}, {{-1.0, 2.0}, 0.25}};
  s.robots.push_back({0.0, -2.5, 0});
  const VisionFrame f = see(s);
  ASSERT_GT(f.obstacles.size(), 10u);
  std::vector<Scene::Obstacle> all = s.obstacles;
  all.push_back({{0.0, -2.5}, s.robot_radius_m});
  for (const auto& p : f.obstacles) {
    // On some circle...
    double best = 1e9;
    for (const auto& o : all) best = std::min(best, std::fabs((p - o.centre).norm() - o.radius_m));
    EXPECT_LT(best, 1e-9);
    // ... and no circle crosses the ray before it.
    const Eigen::Vector2d dir = p.normalized();
    for (const auto& o : all) {
      const double b = dir.dot(o.centre);
      const double disc = b * b - (o.centre.squaredNorm() - o.radius_m * o.radius_m);
      if (disc >= 0) {
        EXPECT_GE(b - std::sqrt(disc), p.norm() - 1e-9);
      }
    }
  }
}

TEST_F(VisionTest, EverySensorThatCrossesAnObstacleReportsItsNearestCrossing) {
  // Vision tests a circle only with the sensors within the angle it covers
  // (found with a rough arctangent and a margin); here every sensor is tested
  // against every circle, in random scenes, and the two must agree.
  std::mt19937 pick(11);
  std::uniform_real_distribution<double> coord(-5.0, 5.0);
  const int n = vision_.params().obstacle_sensors;
  int points = 0;
  for (int scene = 0; scene < 400; ++scene) {
    Scene s = scene_with({coord(pick), coord(pick), coord(pick)});
    std::vector<Scene::Obstacle> all;
    while (all.size() < 8) {
      const Eigen::Vector2d c(coord(pick), coord(pick));
      const double r = all.size() % 2 == 0 ? s.robot_radius_m : 0.1 + 0.3 * (coord(pick) + 5) / 10;
      if ((c - Eigen::Vector2d(s.robots[0].x_m, s.robots[0].y_m)).norm() < r + 0.05) continue;
      all.push_back({c, r});
      if (all.size() % 2 == 1) {
        s.robots.push_back({c.x(), c.y(), 0});
      } else {
        s.obstacles.push_back(all.back());
      }
    }
    const VisionFrame f = see(s);
    std::vector<Eigen::Vector2d> expected;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * kPi * i / n;
      const Eigen::Vector2d dir(std::cos(a), std::sin(a));
      double nearest = std::numeric_limits<double>::infinity();
      for (const Scene::Obstacle& o : all) {
        const Eigen::Vector2d c = Vision::to_robot(s.robots[0], o.centre);
        const double b = dir.dot(c);
        const double disc = b * b - (c.squaredNorm() - o.radius_m * o.radius_m);
        if (b < 0 || disc < 0) continue;
        const double t = b - std::sqrt(disc);
        if (t >= 0) nearest = std::min(nearest, t);
      }
      if (nearest <= vision_.params().obstacle_range_m) expected.push_back(dir * nearest);
    }
    ASSERT_EQ(f.obstacles.size(), expected.size()) << "scene " << scene;
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_LT((f.obstacles[k] - expected[k]).norm(), 1e-9) << "scene " << scene << ", point " << k;
    }
    points += static_cast<int>(expected.size());
  }
  EXPECT_GT(points, 400 * 10) << "the scenes put obstacles in sight";
}

TEST_F(VisionTest, AnObstacleFullyBehindAnotherIsNotReported) {
  Scene s = scene_with({0, 0, 0});
  s.obstacles = {{{2.0, 0.0}, 0.3}, {{4.0, 0.0}, 0.2}};  // the far one fits in the near one's shadow
  const VisionFrame f = see(s);
  ASSERT_FALSE(f.obstacles.empty());
  for (const auto& p : f.obstacles) EXPECT_LT(p.norm(), 2.5) << "a point on the hidden obstacle";
}

TEST_F(VisionTest, LinePointsInAShadowAreNotReported) {
  Scene s = scene_with({-3, 0, 0});
  const std::size_t open = see(s).lines.size();
  s.obstacles = {{{-2.0, 0.0}, 0.3}};  // right in front of the robot, on the way to the halfway line
  const VisionFrame f = see(s);
  EXPECT_LT(f.lines.size(), open);
  for (const auto& p : f.lines) {
    const Eigen::Vector2d w = Vision::to_world(s.robots[0], p);
    const double bearing = std::atan2(w.y(), w.x() + 3);
    const double half = std::asin(0.3 / 1.0);
    EXPECT_FALSE(std::fabs(bearing) < half - 1e-6 && (w - Eigen::Vector2d(-3, 0)).norm() > 1.0)
        << "behind the obstacle";
  }
}

TEST_F(VisionTest, BallOnTheGroundIsSeenAndBehindAnObstacleIsNot) {
  Scene s = scene_with({0, 0, 0});
  s.ball = {2.0, 1.0, 0.11};
  VisionFrame f = see(s);
  ASSERT_EQ(f.balls.size(), 1u);
  EXPECT_NEAR((Vision::to_world(s.robots[0], f.balls[0]) - Eigen::Vector2d(2.0, 1.0)).norm(), 0, 1e-9);
  s.obstacles = {{{1.0, 0.5}, 0.25}};
  f = see(s);
  EXPECT_TRUE(f.balls.empty()) << "hidden by the obstacle";
}

TEST_F(VisionTest, BallInTheAirIsProjectedToTheGroundAndTheSeeLimitHoldsOnBothSides) {
  const double h = vision_.params().camera_height_m;
  const double s_lim = vision_.params().ball_see_limit_m;
  Scene s = scene_with({0, 0, 0});
  const double d_prime = 2.0;
  const double h_prime = 0.3;
  s.ball = {d_prime, 0, 0.11 + h_prime};
  VisionFrame f = see(s);
  ASSERT_EQ(f.balls.size(), 1u);
  EXPECT_NEAR(f.balls[0].norm(), h * d_prime / (h - h_prime), 1e-9);
  // Visible only if h' < -h d' / s + h: put the ball just below and just above that height.
  const double limit = -h * d_prime / s_lim + h;
  s.ball.z() = 0.11 + limit - 1e-3;
  EXPECT_EQ(see(s).balls.size(), 1u) << "just below the see limit";
  s.ball.z() = 0.11 + limit + 1e-3;
  EXPECT_TRUE(see(s).balls.empty()) << "just above the see limit";
}

TEST_F(VisionTest, WithTheCapReachedThePassesStillCoverTheWholeCircle) {
  VisionParams p;
  p.max_line_points = 30;
  p.circle_radii_m = {};
  const Vision small(p, vision_.markings());
  Scene s = scene_with({0.5, 0.3, 0});  // centre of the field: lines all around
  NoiseEngine rng(1);
  const VisionFrame f = small.see(s, 0, rng);
  ASSERT_EQ(f.lines.size(), 30u);
  // The points' bearings leave no gap wider than a quarter turn.
  std::vector<double> bearings;
  for (const auto& q : f.lines) bearings.push_back(std::atan2(q.y(), q.x()));
  std::sort(bearings.begin(), bearings.end());
  double widest = bearings.front() + 2 * kPi - bearings.back();
  for (std::size_t i = 1; i < bearings.size(); ++i) widest = std::max(widest, bearings[i] - bearings[i - 1]);
  EXPECT_LT(widest, kPi / 2);
}

TEST_F(VisionTest, CircularSensorsSeeTheCentreCircleFromOnIt) {
  Scene s = scene_with({2.0, 0.0, 0.4});  // standing on the centre circle
  const VisionFrame f = see(s);
  int on_circle = 0;
  for (const auto& p : f.lines) {
    const Eigen::Vector2d w = Vision::to_world(s.robots[0], p);
    if (std::fabs(w.norm() - 2.0) < 1e-6 && std::fabs(w.x()) > 1e-3) ++on_circle;
  }
  EXPECT_GE(on_circle, 4) << "points of the centre circle";
  VisionParams radial_only;
  radial_only.circle_radii_m = {};
  const Vision r(radial_only, vision_.markings());
  NoiseEngine rng(1);
  const VisionFrame g = r.see(s, 0, rng);
  int radial_on_circle = 0;
  for (const auto& p : g.lines) {
    const Eigen::Vector2d w = Vision::to_world(s.robots[0], p);
    if (std::fabs(w.norm() - 2.0) < 1e-6) ++radial_on_circle;
  }
  EXPECT_GT(on_circle, radial_on_circle) << "the circular sensors add what radial ones miss";
}

TEST_F(VisionTest, NoiseAndDetectionProbabilityChangeTheOutput) {
  VisionParams p;
  p.point_noise_m = 0.05;
  p.detection_probability = 0.5;
  const Vision noisy(p, vision_.markings());
  Scene s = scene_with({-3, 0, 0.3});
  NoiseEngine rng(3);
  const VisionFrame f = noisy.see(s, 0, rng);
  const VisionFrame exact = see(s);
  EXPECT_LT(f.lines.size(), exact.lines.size() * 3 / 4);
  double off = 0;
  for (const auto& q : f.lines) {
    const Eigen::Vector2d w = Vision::to_world(s.robots[0], q);
    off = std::max(off, vision_.markings().distance_to_nearest(w.x(), w.y()));
  }
  EXPECT_GT(off, 0.02) << "noisy points are off the lines";
}

TEST(VisionRunner, LatencyDeliversTheOlderWorld) {
  physics::WorldParams wp;
  wp.robots = {physics::Placement{0, 0, 0}};
  wp.ball_start = {0, 2, 0.11};
  physics::World world(wp);
  VisionParams vp;
  vp.latency_s = 0.2;
  std::vector<Eigen::Vector2d> seen;
  std::vector<double> times;
  VisionRunner runner({Vision(vp, world.markings())}, [&](std::size_t, const VisionFrame& f, double t) {
    if (!f.balls.empty()) seen.push_back(f.balls[0]);
    times.push_back(t);
  });
  for (int i = 0; i < 30; ++i) {
    world.step();
    runner.on_step(world);
  }
  world.place_ball({1.5, 2.0, 0.11});  // moves at t = 0.3 s
  for (int i = 0; i < 15; ++i) {
    world.step();
    runner.on_step(world);
  }
  // Frames at 30 Hz; for 0.2 s after the move they still show the old place.
  ASSERT_FALSE(seen.empty());
  EXPECT_NEAR(seen.back().norm(), 2.0, 1e-3) << "0.15 s after the move: still the old ball";
  EXPECT_LE(times.back(), world.time_s() - 0.2 + 1e-9);
  for (int i = 0; i < 15; ++i) {
    world.step();
    runner.on_step(world);
  }
  EXPECT_NEAR((seen.back() - Eigen::Vector2d(1.5, 2.0)).norm(), 0, 1e-3) << "then the new place";
  EXPECT_NEAR(static_cast<double>(runner.frames()), 60 * 0.01 * 30, 2) << "about 30 frames per second";
}

// Writing the frames into VISION_INFO and waking the agent is the laptop
// link's (tests/emulator/laptop_link_test.cpp); here, each robot's own frame.
TEST(VisionRunner, HandsEachRobotItsOwnFrame) {
  physics::WorldParams wp;
  wp.robots = {physics::Placement{-3, 0, -90}, physics::Placement{1, 2, 0}};  // 4.5 m apart
  wp.ball_start = {-1, 0.5, 0.11};
  physics::World world(wp);
  std::vector<std::size_t> robots;
  std::vector<VisionFrame> frames;
  VisionRunner runner({Vision({}, world.markings()), Vision({}, world.markings())},
                      [&](std::size_t robot, const VisionFrame& f, double) {
                        robots.push_back(robot);
                        frames.push_back(f);
                      });
  world.step();
  runner.on_step(world);
  ASSERT_EQ(robots, (std::vector<std::size_t>{0, 1})) << "one frame each, the first step";
  const VisionFrame& first = frames[0];
  ASSERT_EQ(first.balls.size(), 1u);
  // Robot 0 faces world +x: the ball, 2 m ahead and 0.5 m to the left, is at (-0.5, 2) in its frame.
  EXPECT_NEAR(first.balls[0].x(), -0.5, 1e-4);
  EXPECT_NEAR(first.balls[0].y(), 2.0, 1e-4);
  EXPECT_GT(first.lines.size(), 20u);
  EXPECT_FALSE(first.obstacles.empty()) << "the other robot";
  EXPECT_FALSE(frames[1].lines.empty()) << "robot 1's own frame";
  EXPECT_EQ(runner.frames(), 2u);
}

}  // namespace
}  // namespace canhil::vision_emu
