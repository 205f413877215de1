// canhil/frames/frame.hpp — a classic CAN frame as the rest of canhil sees it.
//
// Plain value type, no sockets, no clocks. The same layout serves data,
// remote and error frames; see FrameKind. Thread-compatible (no shared state).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <initializer_list>

#include "canhil/base/time.hpp"

namespace canhil::frames {


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

/// Error classes and protocol-error details of linux/can/error.h that canhil
/// produces (the error-frame fault) and recognises.
inline constexpr std::uint32_t kErrorClassProtocol = 0x08u;  ///< CAN_ERR_PROT: data[2], data[3] say what and where
inline constexpr std::uint32_t kErrorClassBusError = 0x80u;  ///< CAN_ERR_BUSERROR
inline constexpr std::uint8_t kProtocolErrorBit = 0x01;      ///< CAN_ERR_PROT_BIT, in data[2]
inline constexpr std::uint8_t kProtocolLocationCrc = 0x08;   ///< CAN_ERR_PROT_LOC_CRC_SEQ, in data[3]

/// The error frame a bit error in a frame's CRC sequence gives, as SocketCAN
/// reports it: protocol violation and bus error, all 8 data bytes.
constexpr CanFrame make_bus_error_frame() {
  CanFrame f;
  f.kind = FrameKind::kError;
  f.id = kErrorClassProtocol | kErrorClassBusError;
  f.len = kMaxDataBytes;
  f.data[2] = kProtocolErrorBit;
  f.data[3] = kProtocolLocationCrc;
  return f;
}

/// A frame together with the time it was sent or received.
struct TimedFrame {
  CanFrame frame;
  Nanos time{0};
};

}  // namespace canhil::frames
