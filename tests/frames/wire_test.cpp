#include "canhil/frames/wire.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

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

// An independent count of a frame's bits, written from the standard's text
// (ISO 11898-1:2015 clauses 10.4 and 10.5; Bosch CAN 2.0 part A section 3.1
// and part B section 3.1; reference-figures.md "The CAN wire"): the fields as
// a list of bits, the CRC by polynomial long division over that list, the
// stuff bits inserted into it, and its length. No code shared with wire.cpp.
using Bits = std::vector<int>;

void append(Bits& out, std::uint64_t value, int count) {
  for (int i = count - 1; i >= 0; --i) out.push_back(static_cast<int>((value >> i) & 1u));
}

// Remainder of (message * x^width) divided by the generator (width + 1 bits,
// top bit set), with `initial` XORed into the first `width` message bits.
std::uint64_t long_division(Bits message, std::uint64_t generator, int width, std::uint64_t initial) {
  for (int i = 0; i < width && i < static_cast<int>(message.size()); ++i) {
    message[static_cast<std::size_t>(i)] ^= static_cast<int>((initial >> (width - 1 - i)) & 1u);
  }
  if (static_cast<int>(message.size()) < width) {
    // Shorter than the register: the initial bits past the message stay.
    for (int i = static_cast<int>(message.size()); i < width; ++i) message.push_back(0);
  }
  message.insert(message.end(), static_cast<std::size_t>(width), 0);
  for (std::size_t i = 0; i + static_cast<std::size_t>(width) < message.size(); ++i) {
    if (message[i] == 0) continue;
    for (int k = 0; k <= width; ++k)
      message[i + static_cast<std::size_t>(k)] ^= static_cast<int>((generator >> (width - k)) & 1u);
  }
  std::uint64_t r = 0;
  for (std::size_t i = message.size() - static_cast<std::size_t>(width); i < message.size(); ++i)
    r = (r << 1) | static_cast<std::uint64_t>(message[i]);
  return r;
}

// Inserts a stuff bit after every five equal bits; returns how many.
int stuff(const Bits& in, Bits& out, bool drop_last_due) {
  int count = 0, run = 0, last = -1;
  for (std::size_t i = 0; i < in.size(); ++i) {
    out.push_back(in[i]);
    run = in[i] == last ? run + 1 : 1;
    last = in[i];
    if (run == 5) {
      if (drop_last_due && i + 1 == in.size()) break;
      out.push_back(1 - last);
      ++count;
      last = 1 - last;
      run = 1;
    }
  }
  return count;
}

struct Independent {
  std::uint32_t total = 0;
  std::uint32_t fast = 0;
};

Independent independent_count(const WireFrame& f) {
  static const int kFdLengths[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  int dlc = f.len;
  if (f.fd) {
    dlc = 0;
    while (kFdLengths[dlc] < f.len) ++dlc;
  } else if (f.len8_dlc > 8) {
    dlc = f.len8_dlc;
  }
  const int data_bytes = f.fd ? kFdLengths[dlc] : (f.remote ? 0 : f.len);
  Bits head;  // SOF .. data, unstuffed
  head.push_back(0);
  const std::uint32_t base = f.extended ? f.id >> 18 : f.id;
  append(head, base, 11);
  std::size_t brs_at = 0;
  if (f.extended) {
    append(head, 0b11, 2);  // SRR, IDE
    append(head, f.id & 0x3FFFF, 18);
  }
  head.push_back(f.remote && !f.fd ? 1 : 0);  // RTR / RRS
  if (!f.extended) head.push_back(0);         // IDE
  if (f.fd) {
    append(head, 0b10, 2);  // FDF, res
    brs_at = head.size();
    head.push_back(f.brs);
    head.push_back(f.esi);
  } else {
    append(head, 0, f.extended ? 2 : 1);  // r1 r0, or r0
  }
  append(head, static_cast<std::uint64_t>(dlc), 4);
  for (int i = 0; i < data_bytes; ++i) append(head, f.data[static_cast<std::size_t>(i)], 8);
  Independent r;
  if (!f.fd) {
    Bits region = head;
    append(region, long_division(head, 0xC599, 15, 0), 15);
    Bits stuffed;
    stuff(region, stuffed, false);
    r.total = static_cast<std::uint32_t>(stuffed.size()) + 13;
    return r;
  }
  Bits stuffed;
  stuff(head, stuffed, true);
  // Where BRS lands in the stuffed stream: count up to it.
  Bits upto(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(brs_at + 1));
  Bits upto_stuffed;
  stuff(upto, upto_stuffed, false);
  const int width = data_bytes <= 16 ? 17 : 21;
  const std::uint32_t crc_field = static_cast<std::uint32_t>(4 + width + (4 + width + 3) / 4);
  r.total = static_cast<std::uint32_t>(stuffed.size()) + crc_field + 13;
  if (f.brs) r.fast = static_cast<std::uint32_t>(stuffed.size() - upto_stuffed.size()) + crc_field;
  return r;
}

WireFrame random_frame(std::mt19937& rng) {
  static const std::uint8_t kFdLengths[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  WireFrame w;
  w.extended = (rng() & 1u) != 0;
  w.id = static_cast<std::uint32_t>(rng()) & (w.extended ? kExtendedIdMask : kStandardIdMask);
  const std::uint32_t shape = rng() % 4;  // data, remote, FD, FD with BRS
  w.fd = shape >= 2;
  w.brs = shape == 3;
  w.esi = w.fd && (rng() & 1u) != 0;
  w.remote = shape == 1;
  w.len = w.fd ? kFdLengths[rng() % 16] : static_cast<std::uint8_t>(rng() % 9);
  if (!w.fd && w.len == 8 && rng() % 4 == 0) w.len8_dlc = static_cast<std::uint8_t>(9 + rng() % 7);
  // Runs: half the payloads random, half mostly zeros or ones (long runs, much stuffing).
  const bool runs = (rng() & 1u) != 0;
  for (auto& b : w.data)
    b = runs ? static_cast<std::uint8_t>(rng() % 8 == 0 ? rng() : (rng() & 1u ? 0xFF : 0x00))
             : static_cast<std::uint8_t>(rng());
  return w;
}

TEST(Wire, ExactBitsEqualAnIndependentCountFor100000RandomFrames) {
  std::mt19937 rng(11);
  for (int i = 0; i < 100'000; ++i) {
    const WireFrame w = random_frame(rng);
    const FrameBits bits = count_bits(w);
    const Independent want = independent_count(w);
    ASSERT_EQ(bits.total(), want.total) << "frame " << i << " id " << w.id << " ext " << w.extended << " fd " << w.fd
                                        << " len " << int(w.len);
    ASSERT_EQ(bits.fast, want.fast) << "frame " << i;
    if (!w.fd) {
      const std::uint8_t bytes = w.remote ? 0 : w.len;
      ASSERT_GE(bits.total(), best_case_frame_bits(bytes, w.extended)) << "frame " << i;
      ASSERT_LE(bits.total(), worst_case_frame_bits(bytes, w.extended)) << "frame " << i;
    }
  }
}

TEST(Wire, FdFramesTakeTheirFixedStuffBitsAndTheDataRateAfterBrs) {
  WireFrame w;
  w.fd = true;
  w.len = 64;
  for (std::size_t i = 0; i < w.data.size(); ++i)
    w.data[i] = static_cast<std::uint8_t>(0x55);  // alternating: no dynamic stuffing
  w.id = 0x555;
  const FrameBits slow = count_bits(w);
  // SOF 1, id 11, RRS IDE FDF res BRS ESI 6, DLC 4, 512 data; the CRC field:
  // stuff count 4, CRC-21, 7 fixed stuff bits; 13 bits of tail.
  EXPECT_EQ(slow.fast, 0u);
  EXPECT_GE(slow.total(), 1u + 11 + 6 + 4 + 512 + 4 + 21 + 7 + 13);
  w.brs = true;
  const FrameBits fast = count_bits(w);
  EXPECT_EQ(fast.total(), slow.total()) << "the same bits, at another rate";
  EXPECT_GT(fast.fast, 512u + 4 + 21 + 7);
  EXPECT_EQ(bits_to_time(fast, 1'000'000, 4'000'000),
            bits_to_time(fast.nominal, 1'000'000) + bits_to_time(fast.fast, 4'000'000));
  EXPECT_EQ(fd_dlc(13), 10) << "13 bytes go in a 16-byte frame";
  EXPECT_EQ(fd_length(fd_dlc(64)), 64);
}

TEST(Wire, EachBitKnowsItsFieldAsAnErrorFrameNamesIt) {
  WireFrame w;
  w.id = 0x123;
  w.len = 1;
  w.data[0] = 0xA5;
  EXPECT_EQ(bit_at(w, 0).location, kProtocolLocationSof);
  EXPECT_FALSE(bit_at(w, 0).recessive);
  EXPECT_EQ(bit_at(w, 1).location, kProtocolLocationId28To21);
  EXPECT_EQ(bit_at(w, 9).location, kProtocolLocationId20To18);
  EXPECT_EQ(bit_at(w, 12).location, kProtocolLocationRtr);
  const std::uint32_t n = count_bits(w).total();
  EXPECT_EQ(bit_at(w, n - 1).location, kProtocolLocationIntermission);
  EXPECT_EQ(bit_at(w, n - 13).location, kProtocolLocationCrcDelimiter);
  EXPECT_EQ(bit_at(w, n - 12).location, kProtocolLocationAck);
  EXPECT_EQ(bit_at(w, n - 14).location, kProtocolLocationCrc);
  // The stuffed stream never has six equal bits before the CRC delimiter.
  int run = 0, last = -1;
  for (std::uint32_t i = 0; i + 13 < n; ++i) {
    const int level = bit_at(w, i).recessive ? 1 : 0;
    run = level == last ? run + 1 : 1;
    last = level;
    ASSERT_LE(run, 5) << "bit " << i;
  }
}

TEST(Wire, FdCrcsMatchTheCatalogue) {
  // CRC-17/CAN-FD and CRC-21/CAN-FD of "123456789", register from 0
  // (reveng's catalogue: check 0x04F03 and 0x0ED841).
  std::vector<std::uint8_t> bits;
  for (char c : std::string("123456789")) {
    for (int i = 7; i >= 0; --i) bits.push_back(static_cast<std::uint8_t>((c >> i) & 1));
  }
  const auto n = static_cast<std::uint32_t>(bits.size());
  EXPECT_EQ(can_fd_crc(bits.data(), n, 17, false), 0x04F03u);
  EXPECT_EQ(can_fd_crc(bits.data(), n, 21, false), 0x0ED841u);
}

}  // namespace
}  // namespace canhil::frames
