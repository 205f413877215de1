#include "canhil/physics/field.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace canhil::physics {
namespace {

TEST(FieldMarkings, HasEveryLineOfTheField) {
  const FieldMarkings m = field_markings(FieldParams{});
  EXPECT_EQ(m.segments.size(), 5u + 12u) << "4 outer, halfway, 3 per goal area and penalty area at both ends";
  EXPECT_EQ(m.arcs.size(), 5u) << "centre circle and four corner arcs";
  EXPECT_EQ(m.spots.size(), 3u);
  EXPECT_EQ(m.line_width_m, 0.125);
}

TEST(FieldMarkings, DistanceIsZeroOnLinesAndPositiveBetween) {
  const FieldParams f;
  const FieldMarkings m = field_markings(f);
  EXPECT_NEAR(m.distance_to_nearest(9.0, 3.0), 0, 1e-12) << "goal line";
  EXPECT_NEAR(m.distance_to_nearest(0.0, -5.0), 0, 1e-12) << "halfway line";
  EXPECT_NEAR(m.distance_to_nearest(2.0 * std::cos(1.0), 2.0 * std::sin(1.0)), 0, 1e-12) << "centre circle";
  EXPECT_NEAR(m.distance_to_nearest(9.0 - 0.75, 1.0), 0, 1e-12) << "goal area front";
  EXPECT_NEAR(m.distance_to_nearest(-9.0 + 2.25, -3.25), 0, 1e-12) << "penalty area corner";
  const double c = 0.75 / std::sqrt(2.0);
  EXPECT_NEAR(m.distance_to_nearest(9.0 - c, 6.0 - c), 0, 1e-12) << "corner arc";
  EXPECT_NEAR(m.distance_to_nearest(4.0, 3.0), 2.75, 1e-12) << "nearest: the penalty area front at x = 6.75";
  EXPECT_GT(m.distance_to_nearest(5.0, 3.0), 1.0);
}

TEST(FieldMarkings, FollowsTheConfiguredSize) {
  FieldParams f;
  f.length_m = 22;
  f.width_m = 14;
  const FieldMarkings m = field_markings(f);
  EXPECT_NEAR(m.distance_to_nearest(11.0, 0.0), 0, 1e-12);
  EXPECT_NEAR(m.distance_to_nearest(0.0, 7.0), 0, 1e-12);
  EXPECT_NEAR(m.distance_to_nearest(9.0, 5.0), 1.75, 1e-12) << "nearest: the penalty area side at y = 3.25";
}

}  // namespace
}  // namespace canhil::physics
