#include "canhil/frames/wire.hpp"

#include <array>

namespace canhil::frames {
namespace {

constexpr std::uint32_t kTailBits = 1 + 1 + 1 + 7 + 3;  // CRC delimiter, ACK slot, ACK delimiter, EOF, IFS

// Bits of the stuffed region (SOF to the end of the CRC), one per byte.
struct BitBuffer {
  std::array<std::uint8_t, 160> bits{};
  std::uint32_t n = 0;
  void put(std::uint32_t value, int count) {
    for (int i = count - 1; i >= 0; --i) bits[n++] = static_cast<std::uint8_t>((value >> i) & 1u);
  }
};

}  // namespace

std::uint16_t can_crc15(const std::uint8_t* bits, std::uint32_t count) noexcept {
  std::uint16_t crc = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    const bool next = ((crc >> 14) & 1u) != bits[i];
    crc = static_cast<std::uint16_t>((crc << 1) & 0x7FFF);
    if (next) crc ^= 0x4599;
  }
  return crc;
}

std::uint32_t frame_bits(const CanFrame& f) noexcept {
  if (f.kind == FrameKind::kError) return kErrorFrameBits;
  BitBuffer b;
  const bool remote = f.kind == FrameKind::kRemote;
  const std::uint32_t dlc = f.len8_dlc > 8 ? f.len8_dlc : f.len;
  b.put(0, 1);  // SOF
  if (!f.extended) {
    b.put(f.id & kStandardIdMask, 11);
    b.put(remote ? 1 : 0, 1);  // RTR
    b.put(0, 1);               // IDE
    b.put(0, 1);               // r0
  } else {
    b.put((f.id >> 18) & 0x7FF, 11);
    b.put(1, 1);  // SRR
    b.put(1, 1);  // IDE
    b.put(f.id & 0x3FFFF, 18);
    b.put(remote ? 1 : 0, 1);
    b.put(0, 2);  // r1, r0
  }
  b.put(dlc, 4);
  if (!remote) {
    for (std::uint8_t i = 0; i < f.len && i < kMaxDataBytes; ++i) b.put(f.data[i], 8);
  }
  b.put(can_crc15(b.bits.data(), b.n), 15);
  // Stuffing: after five equal bits, one of the opposite value (which counts
  // towards the next run).
  std::uint32_t stuffed = 0;
  std::uint8_t last = 2;
  int run = 0;
  for (std::uint32_t i = 0; i < b.n; ++i) {
    if (b.bits[i] == last) {
      ++run;
    } else {
      last = b.bits[i];
      run = 1;
    }
    if (run == 5) {
      ++stuffed;
      last = static_cast<std::uint8_t>(1 - last);
      run = 1;
    }
  }
  return b.n + stuffed + kTailBits;
}

std::uint32_t best_case_frame_bits(std::uint8_t data_bytes, bool extended) noexcept {
  const std::uint32_t region = (extended ? 54u : 34u) + 8u * data_bytes;
  return region + kTailBits;
}

std::uint32_t worst_case_frame_bits(std::uint8_t data_bytes, bool extended) noexcept {
  const std::uint32_t region = (extended ? 54u : 34u) + 8u * data_bytes;
  return region + (region - 1) / 4 + kTailBits;
}

}  // namespace canhil::frames
