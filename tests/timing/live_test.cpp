// A bus measured as it runs: load and per-message jitter over whole windows.
#include "canhil/timing/live.hpp"

#include <gtest/gtest.h>

#include "canhil/frames/wire.hpp"
#include "support/test_paths.hpp"

namespace canhil::timing {
namespace {

using namespace std::chrono_literals;

TEST(LiveBusStats, LoadAndWorstPeriodDeviationPerWholeWindow) {
  const auto set = frames::MessageSet::load(test::shipped_dbc());
  LiveBusStats stats(set, 1'000'000, 100ms);
  const frames::MessageCodec* m1 = set->codec().find("M1");
  ASSERT_NE(m1, nullptr);
  const Nanos period = set->ftt(*m1).period;
  ASSERT_GT(period, 0ns);
  frames::CanFrame f;
  f.id = m1->id();
  f.len = 8;
  const std::uint32_t bits = frames::frame_bits(f);
  // Every period on time, but one frame 2 ms late.
  int count = 0;
  for (Nanos t = 0ns; t < 100ms; t += period, ++count) {
    stats.add({f, t == 2 * period ? t + 2ms : t});
  }
  EXPECT_EQ(stats.load(), 0);  // the first window is not whole yet
  stats.advance(100ms);
  EXPECT_EQ(stats.frames(), static_cast<std::uint64_t>(count));
  EXPECT_NEAR(stats.load(), static_cast<double>(count) * bits / 100e3, 1e-12);
  ASSERT_EQ(stats.jitter_ms().size(), 1u);
  EXPECT_EQ(stats.jitter_ms()[0].first, "M1");
  EXPECT_NEAR(stats.jitter_ms()[0].second, 2.0, 1e-9);
  stats.advance(250ms);  // quiet windows: no load, no jitter
  EXPECT_EQ(stats.load(), 0);
  EXPECT_TRUE(stats.jitter_ms().empty());
}

}  // namespace
}  // namespace canhil::timing
