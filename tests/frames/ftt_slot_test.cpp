// A slave's FTT slots (frames/ftt_slot.hpp), each boundary from both sides:
// the synchronous window's start, the asynchronous window's end, the minimum
// gap of a sporadic message, and the slot it takes after a TM.
#include "canhil/frames/ftt_slot.hpp"

#include <gtest/gtest.h>

#include "canhil/frames/wire.hpp"

namespace canhil::frames {
namespace {

using namespace std::chrono_literals;

constexpr Nanos kEc = 10ms;
constexpr Nanos kTmWire = 135us;  // an 8-byte frame's worst case at 1 Mbit/s
constexpr Tm tm_with_window(std::uint16_t window_us) { return Tm{7, 0x1, window_us}; }

TEST(FttSlot, TheEcStartsAtTheTmsStampOrItsWireTimeBeforeAnEndOfFrameStamp) {
  const CanFrame tm = make_data_frame(0x010, {0, 0, 0xFF, 3, 0, 0, 0x5A, 5});
  FttConfig instant;  // a vcan: the write is the send, the stamp the TM's first bit
  EXPECT_EQ(ec_start(tm, 10ms, instant), 10ms);
  FttConfig wire;
  wire.stamps = StampAt::kEndOfFrame;  // a controller's receive stamp, at the end of frame
  wire.bit_rate = 500'000;
  const Nanos on_wire = bits_to_time(frame_bits(tm) - 3, 500'000);  // up to its end of frame: no intermission
  EXPECT_EQ(ec_start(tm, 10ms + on_wire, wire), 10ms);
  EXPECT_NE(ec_start(tm, 10ms + on_wire - 1ns, wire), 10ms) << "a nanosecond earlier: another EC start";
}

TEST(FttSlot, TheSynchronousWindowStartsItsLengthBeforeTheEcEnds) {
  EXPECT_EQ(sync_window_start(tm_with_window(290), 1s, kEc), 1s + 10ms - 290us);
  EXPECT_EQ(sync_window_start(tm_with_window(0), 1s, kEc), 1s + 10ms);
}

TEST(FttSlot, TheAsynchronousWindowEndsWhereTheSynchronousOneStartsOrNeverWithoutOne) {
  EXPECT_EQ(async_window_end(tm_with_window(290), 1s, kEc), 1s + 10ms - 290us);
  EXPECT_EQ(async_window_end(tm_with_window(0), 1s, kEc), kNever) << "a TM that schedules nothing: all asynchronous";
}

TEST(FttSlot, AMinimumGapIsKeptFromItsLengthOnAndNotANanosecondBefore) {
  EXPECT_FALSE(keeps_min_gap(1s + 100ms - 1ns, 1s, 100ms));
  EXPECT_TRUE(keeps_min_gap(1s + 100ms, 1s, 100ms));
  EXPECT_TRUE(keeps_min_gap(1s, kLongAgo, 100ms)) << "never sent";
}

TEST(FttSlot, ASporadicMessageGoesWhenTheTmHasLeftTheWireOnceItsGapHasPassedByTheTm) {
  EXPECT_EQ(async_slot(2s, kTmWire, 2s - 500ms, 500ms), 2s + kTmWire) << "the gap passed at the TM";
  EXPECT_EQ(async_slot(2s, kTmWire, 2s - 500ms + 1ns, 500ms), kNever) << "a nanosecond short: a later EC";
  EXPECT_EQ(async_slot(2s, kTmWire, kLongAgo, 500ms), 2s + kTmWire) << "never sent";
}

}  // namespace
}  // namespace canhil::frames
