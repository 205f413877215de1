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

/// Error frames, as linux/can/error.h has them (one set of constants for all
/// of canhil): the flag that marks an error frame's id (CAN_ERR_FLAG), the
/// class bits in its low 29 bits (CAN_ERR_*, also a socket's error mask), and
/// the protocol-error details canhil produces (the error-frame fault).
inline constexpr std::uint32_t kErrorFlag = 0x2000'0000u;            ///< CAN_ERR_FLAG
inline constexpr std::uint32_t kErrorClassMask = 0x1FFF'FFFFu;       ///< CAN_ERR_MASK: every class
inline constexpr std::uint32_t kErrorClassTxTimeout = 0x001u;        ///< CAN_ERR_TX_TIMEOUT
inline constexpr std::uint32_t kErrorClassLostArbitration = 0x002u;  ///< CAN_ERR_LOSTARB
inline constexpr std::uint32_t kErrorClassController = 0x004u;       ///< CAN_ERR_CRTL
inline constexpr std::uint32_t kErrorClassProtocol = 0x008u;     ///< CAN_ERR_PROT: data[2], data[3] say what and where
inline constexpr std::uint32_t kErrorClassTransceiver = 0x010u;  ///< CAN_ERR_TRX
inline constexpr std::uint32_t kErrorClassNoAck = 0x020u;        ///< CAN_ERR_ACK
inline constexpr std::uint32_t kErrorClassBusOff = 0x040u;       ///< CAN_ERR_BUSOFF
inline constexpr std::uint32_t kErrorClassBusError = 0x080u;     ///< CAN_ERR_BUSERROR
inline constexpr std::uint32_t kErrorClassRestarted = 0x100u;    ///< CAN_ERR_RESTARTED
inline constexpr std::uint8_t kProtocolErrorBit = 0x01;          ///< CAN_ERR_PROT_BIT, in data[2]
inline constexpr std::uint8_t kProtocolLocationCrc = 0x08;       ///< CAN_ERR_PROT_LOC_CRC_SEQ, in data[3]

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
