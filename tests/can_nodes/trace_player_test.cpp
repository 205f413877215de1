// When a recorded bus's frames are due when played again.
#include "canhil/can_nodes/trace_player.hpp"

#include <gtest/gtest.h>

#include "canhil/base/setup_error.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

std::vector<frames::LogEntry> trace(std::initializer_list<Nanos> times) {
  std::vector<frames::LogEntry> out;
  std::uint32_t id = 0x100;
  for (const Nanos t : times) out.push_back({t + 1'700'000'000s, "vcan0", frames::CanFrame{id++, false}});
  return out;
}

TEST(PlaySchedule, DeadlinesFromTheFirstFrameDividedByTheSpeed) {
  PlaySchedule s(trace({0ms, 10ms, 30ms}), 2.0, false);
  EXPECT_EQ(s.span(), 30ms);
  EXPECT_EQ(s.next()->at, 0ms);
  EXPECT_EQ(s.next()->at, 5ms);
  const auto third = s.next();
  EXPECT_EQ(third->at, 15ms);
  EXPECT_EQ(third->entry->frame.id, 0x102u);
  EXPECT_FALSE(s.next());
}

TEST(PlaySchedule, OutOfOrderFramesAreSortedAndLoopsFollowOnAfterOneMeanGap) {
  PlaySchedule s(trace({20ms, 0ms, 10ms}), 0.5, true);
  std::vector<Nanos> at;
  std::vector<std::uint64_t> pass;
  for (int i = 0; i < 6; ++i) {
    const auto d = s.next();
    at.push_back(d->at);
    pass.push_back(d->pass);
  }
  // Half speed: 0, 20, 40 ms; the second pass starts at (20 + 10) / 0.5 = 60 ms.
  EXPECT_EQ(at, (std::vector<Nanos>{0ms, 20ms, 40ms, 60ms, 80ms, 100ms}));
  EXPECT_EQ(pass, (std::vector<std::uint64_t>{0, 0, 0, 1, 1, 1}));
}

TEST(PlaySchedule, NothingToPlayOrABadSpeedIsAnError) {
  EXPECT_THROW(PlaySchedule({}, 1, false), SetupError);
  EXPECT_THROW(PlaySchedule(trace({0ms}), 0, false), SetupError);
  EXPECT_THROW(PlaySchedule(trace({0ms}), -1, false), SetupError);
}

}  // namespace
}  // namespace canhil::can_nodes
