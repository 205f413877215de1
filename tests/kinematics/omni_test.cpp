#include "canhil/kinematics/omni.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace canhil::kinematics {
namespace {

TEST(OmniKinematics, DriveDirectionsAreTheReferenceOnes) {
  const OmniKinematics k;
  const double s3 = std::sqrt(3.0) / 2.0;
  EXPECT_NEAR(k.drive_direction(0)[0], -0.5, 1e-12);
  EXPECT_NEAR(k.drive_direction(0)[1], s3, 1e-12);
  EXPECT_NEAR(k.drive_direction(1)[0], -0.5, 1e-12);
  EXPECT_NEAR(k.drive_direction(1)[1], -s3, 1e-12);
  EXPECT_NEAR(k.drive_direction(2)[0], 1.0, 1e-12);
  EXPECT_NEAR(k.drive_direction(2)[1], 0.0, 1e-12);
}

TEST(OmniKinematics, InverseIsTheReferenceFormula) {
  const OmniKinematics k;
  const Twist t{0.3, -0.7, 1.1};
  const WheelSpeeds w = k.inverse(t);
  for (int n = 0; n < 3; ++n) {
    const auto f = k.drive_direction(n);
    EXPECT_NEAR(w[static_cast<std::size_t>(n)], (t.vx_mps * f[0] + t.vy_mps * f[1] + 0.19 * t.va_radps) / 0.0573,
                1e-12);
  }
  // Forward 0.5 m/s: wheels 1 and 2 turn opposite ways, wheel 3 stands still.
  const WheelSpeeds fwd = k.inverse(Twist{0, 0.5, 0});
  EXPECT_NEAR(fwd[0], -fwd[1], 1e-12);
  EXPECT_NEAR(fwd[2], 0.0, 1e-12);
  // Pure rotation: all wheels equal.
  const WheelSpeeds rot = k.inverse(Twist{0, 0, 2.0});
  EXPECT_NEAR(rot[0], 2.0 * 0.19 / 0.0573, 1e-12);
  EXPECT_NEAR(rot[1], rot[0], 1e-12);
  EXPECT_NEAR(rot[2], rot[0], 1e-12);
}

TEST(OmniKinematics, ForwardInvertsInverseOverManyTwists) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> v(-3, 3);
  for (const OmniGeometry& g :
       {OmniGeometry{}, OmniGeometry{0.05, 0.22, {0, 120, 240}}, OmniGeometry{0.06, 0.2, {45, 135, 270}}}) {
    const OmniKinematics k(g);
    for (int i = 0; i < 1000; ++i) {
      const Twist t{v(rng), v(rng), v(rng)};
      const Twist back = k.forward(k.inverse(t));
      ASSERT_NEAR(back.vx_mps, t.vx_mps, 1e-12);
      ASSERT_NEAR(back.vy_mps, t.vy_mps, 1e-12);
      ASSERT_NEAR(back.va_radps, t.va_radps, 1e-12);
    }
  }
}

TEST(OmniKinematics, DegenerateGeometryIsRefused) {
  EXPECT_THROW(OmniKinematics(OmniGeometry{0.0, 0.19, {30, 150, 270}}), SetupError);
  EXPECT_THROW(OmniKinematics(OmniGeometry{0.05, 0.19, {30, 30, 30}}), SetupError);
}

TEST(EncoderSpec, ReferenceCountsPerTurnAndTick) {
  const EncoderSpec e;
  EXPECT_EQ(e.counts_per_wheel_rev(), 30000.0);
  // 900 counts per 5 ms tick is the set point limit: 6 wheel turns per second.
  EXPECT_NEAR(e.wheel_radps(900), 6.0 * 2.0 * std::numbers::pi, 1e-9);
  EXPECT_NEAR(e.counts_per_tick(e.wheel_radps(123.0)), 123.0, 1e-9);
  EXPECT_NEAR(e.counts(2.0 * std::numbers::pi), 30000.0, 1e-9);
  EXPECT_NEAR(e.wheel_angle_rad(e.counts(1.234)), 1.234, 1e-12);
}

TEST(Integrate, StraightLineAndArcs) {
  // Heading 0: front is world +y.
  Pose p = integrate(Pose{}, Twist{0, 1.0, 0}, 2.0);
  EXPECT_NEAR(p.x_m, 0, 1e-12);
  EXPECT_NEAR(p.y_m, 2.0, 1e-12);
  // Quarter circle: forward 1 m/s while turning pi/2 in 1 s, radius 2/pi.
  p = integrate(Pose{}, Twist{0, 1.0, std::numbers::pi / 2}, 1.0);
  const double radius = 2.0 / std::numbers::pi;
  EXPECT_NEAR(p.x_m, -radius, 1e-12);
  EXPECT_NEAR(p.y_m, radius, 1e-12);
  EXPECT_NEAR(p.heading_rad, std::numbers::pi / 2, 1e-12);
  // Exact for constant twist: many small steps give the same pose as one.
  Pose many;
  for (int i = 0; i < 1000; ++i) many = integrate(many, Twist{0.3, 0.5, 0.7}, 0.001);
  const Pose one = integrate(Pose{}, Twist{0.3, 0.5, 0.7}, 1.0);
  EXPECT_NEAR(many.x_m, one.x_m, 1e-9);
  EXPECT_NEAR(many.y_m, one.y_m, 1e-9);
}

TEST(WrapPi, HalfOpenInterval) {
  EXPECT_NEAR(wrap_pi(3 * std::numbers::pi), std::numbers::pi, 1e-12);
  EXPECT_NEAR(wrap_pi(-std::numbers::pi), std::numbers::pi, 1e-12);
  EXPECT_NEAR(wrap_pi(0.5), 0.5, 1e-12);
  EXPECT_NEAR(wrap_pi(-7.0), -7.0 + 2 * std::numbers::pi, 1e-12);
}

}  // namespace
}  // namespace canhil::kinematics
