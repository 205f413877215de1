#include "canhil/can_nodes/clock.hpp"

#include <gtest/gtest.h>

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

TEST(SimulatedClock, MovesOnlyWhenTold) {
  SimulatedClock clock(1s);
  EXPECT_EQ(clock.now(), 1s);
  EXPECT_EQ(clock.now(), 1s);
  clock.advance(10ms);
  EXPECT_EQ(clock.now(), 1010ms);
  clock.set(2s);
  EXPECT_EQ(clock.now(), 2s);
}

TEST(SimulatedClockDeathTest, NeverRunsBackwards) {
  SimulatedClock clock(1s);
  EXPECT_DEATH(clock.advance(-1ms), "cannot run backwards");
  EXPECT_DEATH(clock.set(0s), "cannot run backwards");
}

TEST(WallClock, IsUnixTimeAndMonotoneEnoughForStamps) {
  const WallClock clock;
  const Nanos a = clock.now();
  const Nanos b = clock.now();
  EXPECT_GE(b, a);
  EXPECT_GT(a, std::chrono::seconds(1'700'000'000)) << "CLOCK_REALTIME, like SocketCAN's timestamps";
}

}  // namespace
}  // namespace canhil::can_nodes
