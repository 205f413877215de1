// canhil/frames/wire.hpp — how long a frame occupies the wire.
//
// vcan has no bit timing, so canhil computes it: the exact number of bits a
// classic CAN frame takes, with its CRC-15 and bit stuffing worked out, and
// the worst case over all payloads. Counts include the 3-bit interframe space,
// so back-to-back frames add up: a standard frame with 8 data bytes takes 111
// to 135 bits (111 to 135 us at 1 Mbit/s). Pure functions.
#pragma once

#include <cstdint>

#include "canhil/frames/frame.hpp"

namespace canhil::frames {

/// An error frame: 6-bit error flag, up to 6 more from the other nodes' flags,
/// 8-bit delimiter, 3-bit interframe space (the longest case).
inline constexpr std::uint32_t kErrorFrameBits = 6 + 6 + 8 + 3;

/// Exact bits on the wire (stuff bits included, interframe space included);
/// kErrorFrameBits for an error frame.
std::uint32_t frame_bits(const CanFrame& frame) noexcept;

/// Most bits any frame of this shape can take (worst-case stuffing).
std::uint32_t worst_case_frame_bits(std::uint8_t data_bytes, bool extended = false) noexcept;

/// Fewest bits (no stuffing at all).
std::uint32_t best_case_frame_bits(std::uint8_t data_bytes, bool extended = false) noexcept;

/// Arbitration order as a number, lower wins: the 11-bit base identifier, then
/// the bit after it (a standard frame's RTR, dominant for data, recessive for
/// a remote frame; an extended frame's SRR, always recessive), then an
/// extended frame's IDE-side 18 bits and its RTR.
constexpr std::uint64_t arbitration_key(std::uint32_t id, bool extended, bool remote = false) noexcept {
  if (!extended) return (static_cast<std::uint64_t>(id & 0x7FFu) << 20) | (std::uint64_t{remote} << 19);
  return (static_cast<std::uint64_t>((id >> 18) & 0x7FFu) << 20) | (1u << 19) |
         (static_cast<std::uint64_t>(id & 0x3FFFFu) << 1) | std::uint64_t{remote};
}

/// Bits at a bit rate, as time.
constexpr Nanos bits_to_time(std::uint32_t bits, std::uint32_t bit_rate) noexcept {
  return Nanos{static_cast<std::int64_t>(bits) * 1'000'000'000 / bit_rate};
}

/// The CAN CRC-15 (polynomial 0x4599) over `count` bits, most significant first.
std::uint16_t can_crc15(const std::uint8_t* bits, std::uint32_t count) noexcept;

}  // namespace canhil::frames
