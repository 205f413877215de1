// The run's clock as the viewer sets it: a plan from the requests and the two
// clocks, checked with wall times the test chooses.
#include "canhil/emulator/run_control.hpp"

#include <gtest/gtest.h>

#include "canhil/base/setup_error.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;
constexpr Nanos kEnd = 100s;

TEST(RunControl, AsFastAsPossibleRunsInSmallWholeChunks) {
  RunControl c(10ms);
  EXPECT_EQ(c.next(0ms, 0ms, kEnd).run_to, RunControl::kChunk);
  EXPECT_EQ(c.next(99'990ms, 0ms, kEnd).run_to, kEnd);  // never past the end
}

TEST(RunControl, PausedNothingRunsAndEachStepIsExactlyOneEc) {
  RunControl c(10ms, 0, /*paused=*/true);
  const auto idle = c.next(40ms, 0ms, kEnd);
  EXPECT_EQ(idle.run_to, 40ms);
  EXPECT_GT(idle.wall_wait, 0ms);
  EXPECT_THROW(c.step(0), SetupError);
  c.step(3);
  for (Nanos t = 40ms; t < 70ms; t += 10ms) EXPECT_EQ(c.next(t, 0ms, kEnd).run_to, t + 10ms);
  EXPECT_EQ(c.next(70ms, 0ms, kEnd).run_to, 70ms);  // the three are spent
  c.resume();
  EXPECT_THROW(c.step(), SetupError);  // stepping needs a pause
  EXPECT_GT(c.next(70ms, 0ms, kEnd).run_to, 70ms);
}

TEST(RunControl, APauseWaitsForTheNextEcBoundary) {
  RunControl c(10ms, 0, true);
  // A run that stands off the grid goes onto it first, whatever the pause says.
  EXPECT_EQ(c.next(43ms, 0ms, kEnd).run_to, 50ms);
}

TEST(RunControl, PacedRunsFollowTheWallClockAtTheSpeedAsked) {
  RunControl c(10ms, 1.0);
  EXPECT_EQ(c.next(0ms, 1000ms, kEnd).run_to, 0ms);  // the pace starts here
  const auto wait = c.next(0ms, 1000ms, kEnd);
  EXPECT_EQ(wait.wall_wait, 10ms);  // the next EC is due in 10 ms
  EXPECT_EQ(c.next(0ms, 1035ms, kEnd).run_to, 30ms);
  c.set_speed(10);
  EXPECT_EQ(c.next(30ms, 2000ms, kEnd).run_to, 30ms);  // a new anchor
  EXPECT_EQ(c.next(30ms, 2010ms, kEnd).run_to, 130ms);
  // Far behind (a slow machine): no burst, the pace starts again from where the run is.
  EXPECT_EQ(c.next(130ms, 5000ms, kEnd).run_to, 130ms);
  EXPECT_EQ(c.next(130ms, 5001ms, kEnd).run_to, 140ms);
  EXPECT_THROW(c.set_speed(-1), SetupError);
  EXPECT_THROW(c.set_speed(5000), SetupError);
  EXPECT_EQ(c.speed(), 10);
}

}  // namespace
}  // namespace canhil::emulator
