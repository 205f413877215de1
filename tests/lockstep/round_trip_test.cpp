// The floor under the lockstep's hand-overs: a child process answers every
// round, and the mean is a real, positive time; no child is left behind.
// (How long it is, is the bench's to print: canhil bench --part external.)
#include "canhil/lockstep/round_trip.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cerrno>

namespace canhil::lockstep {
namespace {

TEST(BareRoundTrip, AChildAnswersEveryRoundAndIsReapedAfter) {
  const std::optional<Nanos> trip = bare_round_trip(200);
  ASSERT_TRUE(trip.has_value());
  EXPECT_GT(*trip, Nanos{0});
  EXPECT_EQ(waitpid(-1, nullptr, WNOHANG), -1) << "the child was reaped";
  EXPECT_EQ(errno, ECHILD);
}

}  // namespace
}  // namespace canhil::lockstep
