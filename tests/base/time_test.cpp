// Seconds and milliseconds into Nanos: exact where Nanos holds the value,
// saturated beyond it, and never undefined (a fuzzed fault time of 1e53 s once was).
#include "canhil/base/time.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace canhil {
namespace {

TEST(Time, SecondsAndMillisecondsConvertAsDurationCastWithinRange) {
  EXPECT_EQ(from_seconds(1.5), Nanos{1'500'000'000});
  EXPECT_EQ(from_seconds(-0.25), Nanos{-250'000'000});
  EXPECT_EQ(from_ms(0.3), std::chrono::duration_cast<Nanos>(std::chrono::duration<double, std::milli>(0.3)));
  EXPECT_EQ(from_ms(10), Nanos{10'000'000});
  EXPECT_EQ(from_seconds(31'536'000), Nanos{31'536'000'000'000'000});  // a year, the faults' limit
  static_assert(from_seconds(2) == Nanos{2'000'000'000}, "usable in constant expressions");
}

TEST(Time, BeyondWhatNanosHoldsItSaturatesAndNanIsZero) {
  EXPECT_EQ(from_seconds(1e53), kNever);
  EXPECT_EQ(from_seconds(-1e53), -kNever);
  EXPECT_EQ(from_seconds(std::numeric_limits<double>::infinity()), kNever);
  EXPECT_EQ(from_seconds(-std::numeric_limits<double>::infinity()), -kNever);
  EXPECT_EQ(from_seconds(std::numeric_limits<double>::quiet_NaN()), Nanos{0});
  EXPECT_EQ(from_ms(1e16), kNever) << "1e13 s";
  EXPECT_EQ(from_ms(-1e16), -kNever);
  EXPECT_EQ(from_ms(std::numeric_limits<double>::quiet_NaN()), Nanos{0});
  // Just inside: 9e9 s is still a number of nanoseconds.
  EXPECT_EQ(from_seconds(9e9), Nanos{9'000'000'000'000'000'000});
}

}  // namespace
}  // namespace canhil
