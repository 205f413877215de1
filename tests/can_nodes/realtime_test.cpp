// The real-time pacer on a clock the test controls: it waits for the earliest
// deadline, sends what is due before it reads, reads a bounded number of
// frames per pass (a flood cannot hold up a deadline) and stops at its end.
#include "canhil/can_nodes/realtime.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

// A clock that only moves when the pacer waits.
class TestClock final : public Clock {
 public:
  Nanos now() const noexcept override { return now_; }
  Nanos now_{0};
};

// Wants a tick at each of its times; has `queued` frames waiting to be read.
class Paced final : public Participant {
 public:
  explicit Paced(std::vector<Nanos> wakes) : wakes_(std::move(wakes)) {}
  std::size_t poll() override { return poll_some(~std::size_t{0}); }
  std::size_t poll_some(std::size_t budget) override {
    const std::size_t n = std::min(budget, queued);
    queued -= n;
    reads.push_back(n);
    return n;
  }
  void tick(Nanos now) override {
    ticks.push_back(now);
    wakes_.erase(wakes_.begin());
  }
  Nanos next_wakeup() const override { return wakes_.empty() ? kNever : wakes_.front(); }

  std::size_t queued = 0;
  std::vector<Nanos> ticks;
  std::vector<std::size_t> reads;

 private:
  std::vector<Nanos> wakes_;
};

TEST(Realtime, WaitsForEachDeadlineAndTicksAtIt) {
  TestClock clock;
  std::vector<Nanos> waited;
  Realtime loop(clock, [&](Nanos deadline) {
    waited.push_back(deadline);
    clock.now_ = deadline;  // the wait returns at the deadline
  });
  Paced p({10ms, 25ms});
  loop.add(p);
  int passes = 0;
  loop.on_pass([&] { ++passes; });
  const std::atomic<bool> stop{false};
  loop.run_until(40ms, stop);
  EXPECT_EQ(waited, (std::vector<Nanos>{10ms, 25ms, 40ms}));
  EXPECT_EQ(p.ticks, (std::vector<Nanos>{10ms, 25ms}));
  EXPECT_EQ(passes, 3) << "the owner's hook once a pass";
  EXPECT_EQ(loop.wakeups(), 3u);
}

TEST(Realtime, AFloodIsReadInBoundedBitesAndNeverDelaysADeadline) {
  TestClock clock;
  Realtime loop(clock, [&](Nanos deadline) {
    clock.now_ = std::min(deadline, clock.now_ + 1ms);  // frames keep arriving: back early
  });
  Paced p({5ms});
  p.queued = 100000;
  loop.add(p);
  const std::atomic<bool> stop{false};
  loop.run_until(5ms, stop);
  ASSERT_EQ(p.ticks.size(), 1u);
  EXPECT_EQ(p.ticks[0], 5ms) << "the tick came on time";
  for (const std::size_t n : p.reads) EXPECT_LE(n, 64u) << "a bounded number of frames per pass";
  EXPECT_GT(p.queued, 0u) << "the rest stays queued for later passes";
}

TEST(Realtime, StopsWhenAsked) {
  TestClock clock;
  std::atomic<bool> stop{false};
  Realtime loop(clock, [&](Nanos) {
    clock.now_ += 1ms;
    if (clock.now_ >= 3ms) stop = true;
  });
  loop.run_until(kNever, stop);
  EXPECT_EQ(clock.now_, 3ms);
}

}  // namespace
}  // namespace canhil::can_nodes
