// Worst-case wire times and the revised CAN response-time analysis (Davis,
// Burns, Bril and Lukkien, Real-Time Systems 35, 2007), on cases worked out by
// hand in the comments: each step of each fixed-point iteration is written out
// so that a reader can check the figure without the code.
#include "canhil/timing/schedulability.hpp"

#include <gtest/gtest.h>

#include "canhil/base/setup_error.hpp"

namespace canhil::timing {
namespace {

using namespace std::chrono_literals;

AnalysedMessage message(const char* name, std::uint32_t id, Nanos c, Nanos t) {
  AnalysedMessage m;
  m.name = name;
  m.id = id;
  m.transmission = c;
  m.period = t;
  return m;
}

const ResponseBound& named(const NativeAnalysis& a, const std::string& name) {
  for (const ResponseBound& m : a.messages) {
    if (m.name == name) return m;
  }
  throw std::runtime_error("no message " + name);
}

TEST(FrameTime, BestAndWorstCaseBitsWithTheInterframeSpace) {
  // Standard, 8 bytes: 34 + 64 = 98 bits under the stuffing rule, 13 after it
  // (CRC delimiter, ACK slot and delimiter, EOF, interframe space): 111 bits;
  // at worst one stuff bit per 4 after the first, (98 - 1) / 4 = 24 more: 135.
  const FrameTime std8 = frame_time(8, false, 1'000'000);
  EXPECT_EQ(std8.best_bits, 111u);
  EXPECT_EQ(std8.worst_bits, 135u);
  EXPECT_EQ(std8.best, 111us);
  EXPECT_EQ(std8.worst, 135us);
  // No data: 34 + 13 = 47 bits, worst (34 - 1) / 4 = 8 more: 55.
  EXPECT_EQ(frame_time(0, false, 1'000'000).worst_bits, 55u);
  EXPECT_EQ(frame_time(0, false, 1'000'000).best_bits, 47u);
  // Extended, 8 bytes: 54 + 64 = 118, + 13 = 131; worst (118 - 1) / 4 = 29 more: 160.
  EXPECT_EQ(frame_time(8, true, 1'000'000).best_bits, 131u);
  EXPECT_EQ(frame_time(8, true, 1'000'000).worst_bits, 160u);
  // 135 bits at 125 kbit/s (8 us a bit): 1.08 ms.
  EXPECT_EQ(frame_time(8, false, 125'000).worst, 1080us);
  EXPECT_THROW(frame_time(9, false, 1'000'000), SetupError);
  EXPECT_THROW(frame_time(8, false, 0), SetupError);
}

TEST(NativeCan, OneMessageTakesItsOwnFrameTimeAndNothingMore) {
  const NativeAnalysis a = analyse_native_can({message("M", 0x100, 135us, 10ms)}, 1'000'000);
  ASSERT_EQ(a.messages.size(), 1u);
  const ResponseBound& m = a.messages[0];
  EXPECT_EQ(m.blocking, 0ns);
  EXPECT_EQ(m.busy_period, 135us);
  EXPECT_EQ(m.instances, 1);
  EXPECT_EQ(m.worst_response, 135us);
  EXPECT_EQ(m.deadline, 10ms) << "the period, when no deadline is given";
  EXPECT_TRUE(m.schedulable);
  EXPECT_EQ(m.margin(), 10ms - 135us);
  EXPECT_DOUBLE_EQ(a.utilisation, 0.0135);
}

TEST(NativeCan, TwoMessagesOfEqualPeriodEachWaitForTheOther) {
  // H (0x10) can find L's frame on the wire when it is queued: blocking 135,
  // then its own 135: 270 us. L has nothing below it; H queued with it, up to
  // a bit time after it, goes first: w = ceil((0 + 1) / 10000) * 135 = 135,
  // stable; R = 135 + 135 = 270 us.
  const NativeAnalysis a =
      analyse_native_can({message("L", 0x20, 135us, 10ms), message("H", 0x10, 135us, 10ms)}, 1'000'000);
  ASSERT_EQ(a.messages.size(), 2u);
  EXPECT_EQ(a.messages[0].name, "H") << "priority order, highest first";
  EXPECT_EQ(named(a, "H").blocking, 135us);
  EXPECT_EQ(named(a, "H").worst_response, 270us);
  EXPECT_EQ(named(a, "L").blocking, 0ns);
  EXPECT_EQ(named(a, "L").worst_response, 270us);
  EXPECT_EQ(named(a, "L").busy_period, 270us);
  EXPECT_TRUE(a.schedulable());
}

// The phenomenon the 2007 paper found in the 1994 analysis (its section 3):
// the worst response of a low-priority message need not be its first instance
// in the busy period, because its own frame, non-preemptive, pushes the next
// higher-priority instances into the window of its next instance. Here three
// messages of 1 ms each, bit time 8 us (125 kbit/s):
//   A: period 2.5 ms, B: 3.5 ms, C: 3.5 ms (priority A > B > C).
// C: busy period t = ceil(t/2.5) + ceil(t/3.5) + ceil(t/3.5) (ms) from t = 1:
//   1 -> 3 -> 4 -> 6 -> 7 -> 7: 7 ms, so 2 instances (ceil(7 / 3.5)).
//   q = 0: w = ceil((w + 0.008)/2.5) + ceil((w + 0.008)/3.5) from 0: 2, stable;
//          R = 2 + 1 = 3 ms (all that the first-instance analysis sees).
//   q = 1: w = 1 + the same from 1: 3 -> 4 -> 5 -> 6 -> 6; R = 6 - 3.5 + 1 = 3.5 ms.
// The schedule at the critical instant agrees: A 0-1, B 1-2, C 2-3, A (2.5)
// 3-4, B (3.5) 4-5, A (5.0) 5-6, C (3.5) 6-7: 3.5 ms after it was queued.
// B: blocking 1 (C); busy period 1 + ceil(t/2.5) + ceil(t/3.5): 1 -> 3 -> 4 -> 5 -> 5,
//   two instances: q = 0: w = 1 + ceil((w + 0.008)/2.5): 1 -> 2 -> 2, R = 3;
//   q = 1: w = 2 + ceil(...): 2 -> 3 -> 4 -> 4, R = 4 - 3.5 + 1 = 1.5. R_B = 3 ms.
// A: blocking 1, busy period 2 ms, one instance: R = 1 + 1 = 2 ms.
TEST(NativeCan, TheWorstInstanceIsTheSecondWhenTheFirstPushesTheOthersOn) {
  const NativeAnalysis a = analyse_native_can(
      {message("A", 1, 1ms, 2500us), message("B", 2, 1ms, 3500us), message("C", 3, 1ms, 3500us)}, 8us);
  const ResponseBound& c = named(a, "C");
  EXPECT_EQ(c.busy_period, 7ms);
  EXPECT_EQ(c.instances, 2);
  EXPECT_EQ(c.worst_instance, 1);
  EXPECT_EQ(c.worst_response, 3500us) << "the first instance alone would give 3 ms";
  EXPECT_EQ(named(a, "B").worst_response, 3ms);
  EXPECT_EQ(named(a, "B").worst_instance, 0);
  EXPECT_EQ(named(a, "B").blocking, 1ms);
  EXPECT_EQ(named(a, "A").worst_response, 2ms);
  EXPECT_TRUE(c.schedulable) << "3.5 ms against a deadline of 3.5 ms: met, with nothing to spare";
  EXPECT_EQ(c.margin(), 0ns);
  // A deadline a quarter millisecond shorter than the period: C misses by it.
  std::vector<AnalysedMessage> tighter{message("A", 1, 1ms, 2500us), message("B", 2, 1ms, 3500us),
                                       message("C", 3, 1ms, 3500us)};
  tighter[2].deadline = 3250us;
  const NativeAnalysis t = analyse_native_can(tighter, 8us);
  EXPECT_FALSE(named(t, "C").schedulable);
  EXPECT_EQ(named(t, "C").margin(), -250us);
  EXPECT_FALSE(t.schedulable());
}

TEST(NativeCan, ABusFullToTheLastBitLeavesTheLowestUnboundedAndTheOthersBounded) {
  // H and L of 1 ms every 2 ms: utilisation exactly 1. H's level is at 0.5:
  // blocking 1 + its own 1 = 2 ms, just inside. L's level never empties.
  const NativeAnalysis a = analyse_native_can({message("H", 1, 1ms, 2ms), message("L", 2, 1ms, 2ms)}, 1us);
  EXPECT_DOUBLE_EQ(a.utilisation, 1.0);
  EXPECT_EQ(named(a, "H").worst_response, 2ms);
  EXPECT_TRUE(named(a, "H").schedulable);
  EXPECT_EQ(named(a, "L").worst_response, kNever);
  EXPECT_EQ(named(a, "L").busy_period, kNever);
  EXPECT_FALSE(named(a, "L").schedulable);
  EXPECT_FALSE(a.schedulable());
}

TEST(NativeCan, QueuingJitterAddsToTheResponseAndToTheInterferenceOnOthers) {
  // H: 1 ms every 10 ms, jitter 9.5 ms: two of its instances can fall within
  // 0.5 ms. L, 1 ms every 10 ms below it: w = ceil((w + 9.5 + 0.001)/10) * 1:
  // 0 -> 1 -> 2 -> 2 (ms), R = 2 + 1 = 3 ms. H itself: R = J + B + C = 9.5 + 1 + 1.
  std::vector<AnalysedMessage> set{message("H", 1, 1ms, 10ms), message("L", 2, 1ms, 10ms)};
  set[0].jitter = 9500us;
  set[0].deadline = 20ms;
  const NativeAnalysis a = analyse_native_can(set, 1us);
  EXPECT_EQ(named(a, "L").worst_response, 3ms);
  EXPECT_EQ(named(a, "H").worst_response, 11500us);
  EXPECT_TRUE(a.schedulable());
}

TEST(NativeCan, AStandardFrameWinsOverAnExtendedOneOfTheSameBaseIdentifier) {
  AnalysedMessage ext = message("ext", 0x100u << 18, 160us, 10ms);
  ext.extended = true;
  AnalysedMessage low_base = message("low base", 0x033u << 18 | 1, 160us, 10ms);
  low_base.extended = true;
  const NativeAnalysis a = analyse_native_can(
      {ext, message("std", 0x100, 135us, 10ms), low_base, message("std 0x123", 0x123, 135us, 10ms)}, 1'000'000);
  ASSERT_EQ(a.messages.size(), 4u);
  EXPECT_EQ(a.messages[0].name, "low base");
  EXPECT_EQ(a.messages[1].name, "std");
  EXPECT_EQ(a.messages[2].name, "ext");
  EXPECT_EQ(a.messages[3].name, "std 0x123");
}

TEST(NativeCan, AMessageWithoutPeriodOrTwoSharingAnIdentifierAreNamed) {
  try {
    analyse_native_can({message("KICK", 0x40, 135us, 0ns)}, 1'000'000);
    FAIL() << "no error";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("KICK (0x040) has no period"), std::string::npos) << e.what();
  }
  try {
    analyse_native_can({message("A", 0x40, 135us, 10ms), message("B", 0x40, 135us, 10ms)}, 1'000'000);
    FAIL() << "no error";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("A (0x040) and B (0x040) share an identifier"), std::string::npos) << e.what();
  }
  EXPECT_THROW(analyse_native_can({message("M", 1, 135us, 10ms)}, 0u), SetupError);
}

}  // namespace
}  // namespace canhil::timing
