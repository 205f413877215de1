// canhil/frames/frame.hpp — a classic CAN frame as the rest of canhil sees it.
//
// Plain value type, no sockets, no clocks. The same layout serves data,
// remote and error frames; see FrameKind. Thread-compatible (no shared state).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <initializer_list>

namespace canhil::frames {

/// Time on a canhil clock: nanoseconds since that clock's epoch. For the wall
/// clock the epoch is the Unix epoch; for a simulated clock it is the start of
/// the run. Received frames carry their time in this unit.
using Nanos = std::chrono::nanoseconds;

inline constexpr std::uint32_t kStandardIdMask = 0x7FFu;
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFF'FFFFu;
/// Error-frame class bits live in the low 29 bits, as in linux/can/error.h.
inline constexpr std::uint32_t kErrorClassMask = 0x1FFF'FFFFu;
inline constexpr std::size_t kMaxDataBytes = 8;

enum class FrameKind : std::uint8_t {
  kData,    ///< ordinary data frame
  kRemote,  ///< remote transmission request; `len` is the requested length, data unused
  kError,   ///< error frame as SocketCAN reports it; `id` holds the CAN_ERR_* class bits
};

struct CanFrame {
  /// 11-bit (extended == false) or 29-bit identifier; for kError the error class bits.
  std::uint32_t id = 0;
  bool extended = false;
  FrameKind kind = FrameKind::kData;
  /// Number of data bytes, 0..8 (for remote frames the requested length).
  std::uint8_t len = 0;
  /// Raw DLC 9..15 of a classic frame with len == 8 (candump's `_X` suffix); 0 otherwise.
  std::uint8_t len8_dlc = 0;
  std::array<std::uint8_t, kMaxDataBytes> data{};

  friend bool operator==(const CanFrame&, const CanFrame&) = default;
};

/// A data frame with the given standard id and bytes (at most 8 are used).
constexpr CanFrame make_data_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  for (std::uint8_t b : bytes) {
    if (f.len == kMaxDataBytes) break;
    f.data[f.len++] = b;
  }
  return f;
}

/// A frame together with the time it was sent or received.
struct TimedFrame {
  CanFrame frame;
  Nanos time{0};
};

}  // namespace canhil::frames
