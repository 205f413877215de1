#include "canhil/frames/wire.hpp"

#include <gtest/gtest.h>

#include <random>

#include "canhil/frames/candump.hpp"

namespace canhil::frames {
namespace {

CanFrame f(const char* compact) {
  CanFrame out;
  EXPECT_TRUE(parse_compact(compact, out));
  return out;
}

TEST(Wire, ReferenceFiguresForEightByteStandardFrames) {
  EXPECT_EQ(best_case_frame_bits(8), 111u);
  EXPECT_EQ(worst_case_frame_bits(8), 135u);
  EXPECT_EQ(bits_to_time(135, 1'000'000), std::chrono::microseconds(135));
  EXPECT_EQ(best_case_frame_bits(0), 47u);
  EXPECT_EQ(worst_case_frame_bits(8, true), 160u);
}

TEST(Wire, ExactCountsStayWithinBestAndWorstCase) {
  std::mt19937 rng(3);
  for (int i = 0; i < 20000; ++i) {
    CanFrame fr;
    fr.extended = (rng() & 1u) != 0;
    fr.id = static_cast<std::uint32_t>(rng()) & (fr.extended ? kExtendedIdMask : kStandardIdMask);
    fr.len = static_cast<std::uint8_t>(rng() % 9);
    for (auto& b : fr.data) b = static_cast<std::uint8_t>(rng());
    const std::uint32_t bits = frame_bits(fr);
    ASSERT_GE(bits, best_case_frame_bits(fr.len, fr.extended));
    ASSERT_LE(bits, worst_case_frame_bits(fr.len, fr.extended));
  }
}

TEST(Wire, StuffingIsCountedForLongRuns) {
  // All-zero payloads and ids force a stuff bit after every five equal bits.
  const std::uint32_t zeros = frame_bits(f("000#0000000000000000"));
  const std::uint32_t mixed = frame_bits(f("555#5555555555555555"));  // alternating bits: little stuffing
  EXPECT_GT(zeros, mixed);
  EXPECT_GT(zeros, 111u + 15u);
  EXPECT_LE(mixed, 111u + 3u);
}

TEST(Wire, AnErrorFrameTakesItsFlagsDelimiterAndInterframeSpace) {
  const CanFrame error = make_bus_error_frame();
  EXPECT_EQ(error.kind, FrameKind::kError);
  EXPECT_EQ(frame_bits(error), 23u) << "6 + 6 flag bits, 8 delimiter, 3 interframe space";
  EXPECT_LT(frame_bits(error), best_case_frame_bits(0)) << "shorter than any data frame";
}

TEST(Wire, Crc15OfAKnownSequence) {
  // CRC-15/CAN of the ASCII bytes "123456789" is 0x059E.
  std::vector<std::uint8_t> bits;
  for (char c : std::string("123456789")) {
    for (int i = 7; i >= 0; --i) bits.push_back(static_cast<std::uint8_t>((c >> i) & 1));
  }
  EXPECT_EQ(can_crc15(bits.data(), static_cast<std::uint32_t>(bits.size())), 0x059E);
}

}  // namespace
}  // namespace canhil::frames
