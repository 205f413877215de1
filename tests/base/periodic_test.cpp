// A period re-armed in one place: due from its first instant, one period on
// after each, past a late `now` in whole periods, and whole periods given up.
#include "canhil/base/periodic.hpp"

#include <gtest/gtest.h>

namespace canhil {
namespace {

using namespace std::chrono_literals;

TEST(Periodic, DueFromItsFirstInstantThenOnePeriodOn) {
  Periodic p(10ms, 5ms);
  EXPECT_FALSE(p.due(4ms));
  EXPECT_TRUE(p.due(5ms));
  p.advance();
  EXPECT_EQ(p.next(), 15ms);
  EXPECT_FALSE(p.due(14ms));
}

TEST(Periodic, TakenLateItMovesPastNowInWholePeriods) {
  Periodic p(10ms, 5ms);
  p.advance_past(5ms);
  EXPECT_EQ(p.next(), 15ms) << "exactly on time: the next one";
  p.advance_past(40ms);
  EXPECT_EQ(p.next(), 45ms) << "15, 25, 35 taken at once: the first after 40";
  p.advance_past(44ms);
  EXPECT_EQ(p.next(), 45ms) << "not due: unchanged";
  p.advance_past(45ms);
  EXPECT_EQ(p.next(), 55ms);
}

TEST(Periodic, GivenUpPeriodsMoveItOnAndANewOneIsNeverDue) {
  Periodic p(10ms, 0ms);
  p.skip(3);
  EXPECT_EQ(p.next(), 30ms);
  EXPECT_FALSE(Periodic().due(kNever - 1ns)) << "none due before it is armed";
}

}  // namespace
}  // namespace canhil
