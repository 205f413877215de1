// canhil/frames/wire.hpp — how long a frame occupies the wire, bit by bit.
//
// vcan has no bit timing, so canhil computes it: a frame's bit stream as a
// controller sends it (ISO 11898-1: classic base and extended frames, remote
// frames, CAN FD frames with and without bit rate switching), with its CRC
// and bit stuffing worked out; the exact number of bits, which of them go at
// the data bit rate, and what field each bit is in (an error frame's place);
// and the best and worst case over all payloads. Counts include the 3-bit
// interframe space, so back-to-back frames add up: a standard frame with 8
// data bytes takes 111 to 135 bits (111 to 135 us at 1 Mbit/s). Pure functions.
//
// What the stream is, field by field (ISO 11898-1:2015, clause 10; Bosch CAN
// 2.0 part A section 3 and part B section 3; the CAN FD specification 1.0):
//   classic base:     SOF, ID 11, RTR, IDE, r0, DLC 4, data, CRC-15
//   classic extended: SOF, ID 11, SRR, IDE, ID 18, RTR, r1, r0, DLC 4, data, CRC-15
//   FD base:          SOF, ID 11, RRS, IDE, FDF, res, BRS, ESI, DLC 4, data
//   FD extended:      SOF, ID 11, SRR, IDE, ID 18, RRS, FDF, res, BRS, ESI, DLC 4, data
// then, classic: the whole of the above stuffed (after five equal bits one of
// the other value, which counts towards the next run); FD: the above stuffed
// likewise, then the stuff count (3 bits, Gray-coded, and a parity bit) and a
// CRC-17 (up to 16 data bytes) or CRC-21 with a fixed stuff bit before the
// stuff count and after every fourth bit (the first fixed stuff bit stands in
// for a dynamic one due after the last data bit); then, unstuffed, CRC
// delimiter, ACK slot, ACK delimiter, 7 bits end of frame, 3 bits
// intermission. With BRS, the bits after BRS up to the CRC delimiter go at the
// data bit rate (the switch at BRS's and the CRC delimiter's sample points is
// counted as whole bits at the nominal rate).
#pragma once

#include <array>
#include <cstdint>

#include "canhil/frames/frame.hpp"

namespace canhil::frames {

/// The interframe space's intermission: the 3 recessive bits after a frame's
/// end of frame (counted in every frame's bits here).
inline constexpr std::uint32_t kIntermissionBits = 3;

/// CAN FD's largest payload.
inline constexpr std::size_t kMaxFdDataBytes = 64;

/// A frame as the wire carries it, classic or CAN FD. Bytes past `len` are not read.
struct WireFrame {
  std::uint32_t id = 0;  ///< 11 or 29 bits
  bool extended = false;
  bool remote = false;        ///< classic only: FD has no remote frames
  bool fd = false;            ///< an FD frame (FDF recessive)
  bool brs = false;           ///< FD: the data phase at the data bit rate
  bool esi = false;           ///< FD: the sender is error-passive
  std::uint8_t len = 0;       ///< data bytes: 0..8 classic, an FD length (fd_length) for FD
  std::uint8_t len8_dlc = 0;  ///< classic with len 8: a raw DLC 9..15 (0: 8)
  std::array<std::uint8_t, kMaxFdDataBytes> data{};
};

/// A classic frame of canhil's as the wire carries it (error frames: a data frame of their bytes).
WireFrame wire_frame(const CanFrame& frame) noexcept;
/// The same into `out` as it stands: its header and its first 8 bytes are
/// set, the bytes past them left as they were (a classic frame has none).
void wire_frame_into(const CanFrame& frame, WireFrame& out) noexcept;

/// The DLC of an FD payload of `len` bytes (a length FD cannot carry: the next one up).
std::uint8_t fd_dlc(std::uint8_t len) noexcept;
/// The bytes an FD DLC stands for (0..8, 12, 16, 20, 24, 32, 48, 64).
std::uint8_t fd_length(std::uint8_t dlc) noexcept;

/// A frame's bits on the wire: `nominal` at the nominal (arbitration) bit rate,
/// `fast` at the data bit rate (FD with BRS only). Intermission included.
struct FrameBits {
  std::uint32_t nominal = 0;
  std::uint32_t fast = 0;
  constexpr std::uint32_t total() const noexcept { return nominal + fast; }
  friend constexpr bool operator==(const FrameBits&, const FrameBits&) = default;
};
FrameBits count_bits(const WireFrame& frame) noexcept;
/// The first `count` bits of the frame on the wire, by rate (the time to a bit).
FrameBits prefix_bits(const WireFrame& frame, std::uint32_t count) noexcept;

/// One bit of a frame as it is on the wire (stuff bits included).
struct WireBit {
  bool recessive = true;
  std::uint8_t location = 0;  ///< the field, as an error frame's data[3] names it (kProtocolLocation*)
  bool fast = false;          ///< at the data bit rate
  bool stuff = false;         ///< a stuff bit (dynamic or fixed)
};
/// Bit `index` of the frame on the wire, SOF being 0; past the last
/// (intermission) bit, a recessive bit of the intermission.
WireBit bit_at(const WireFrame& frame, std::uint32_t index) noexcept;

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
/// A frame's bits at the nominal and the data bit rate (0: the nominal), as time.
constexpr Nanos bits_to_time(FrameBits bits, std::uint32_t bit_rate, std::uint32_t data_bit_rate) noexcept {
  const std::uint32_t fast_rate = data_bit_rate != 0 ? data_bit_rate : bit_rate;
  return Nanos{(static_cast<std::int64_t>(bits.nominal) * 1'000'000'000 / bit_rate) +
               (static_cast<std::int64_t>(bits.fast) * 1'000'000'000 / fast_rate)};
}

/// The CAN CRC-15 (polynomial 0x4599) over `count` bits, most significant first.
std::uint16_t can_crc15(const std::uint8_t* bits, std::uint32_t count) noexcept;
/// CAN FD's CRC-17 (polynomial 0x1685B) or CRC-21 (0x102899), `width` 17 or
/// 21, over `count` bits (the stuffed stream from SOF and the stuff count),
/// first bit first; `iso`: the register starts with its top bit set (ISO
/// 11898-1:2015), else at 0 (Bosch's CAN FD 1.0, the CRC catalogue's check).
std::uint32_t can_fd_crc(const std::uint8_t* bits, std::uint32_t count, int width, bool iso = true) noexcept;

}  // namespace canhil::frames
