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
inline constexpr std::uint32_t kErrorClassCounters = 0x200u;     ///< CAN_ERR_CNT: data[6] TEC, data[7] REC
/// CAN_ERR_CRTL's details, in data[1].
inline constexpr std::uint8_t kControllerRxWarning = 0x04;  ///< CAN_ERR_CRTL_RX_WARNING
inline constexpr std::uint8_t kControllerTxWarning = 0x08;  ///< CAN_ERR_CRTL_TX_WARNING
inline constexpr std::uint8_t kControllerRxPassive = 0x10;  ///< CAN_ERR_CRTL_RX_PASSIVE
inline constexpr std::uint8_t kControllerTxPassive = 0x20;  ///< CAN_ERR_CRTL_TX_PASSIVE
inline constexpr std::uint8_t kControllerActive = 0x40;     ///< CAN_ERR_CRTL_ACTIVE
/// CAN_ERR_PROT's kind, in data[2].
inline constexpr std::uint8_t kProtocolErrorBit = 0x01;    ///< CAN_ERR_PROT_BIT
inline constexpr std::uint8_t kProtocolErrorForm = 0x02;   ///< CAN_ERR_PROT_FORM
inline constexpr std::uint8_t kProtocolErrorStuff = 0x04;  ///< CAN_ERR_PROT_STUFF
inline constexpr std::uint8_t kProtocolErrorBit0 = 0x08;   ///< CAN_ERR_PROT_BIT0: could not send a dominant bit
inline constexpr std::uint8_t kProtocolErrorBit1 = 0x10;   ///< CAN_ERR_PROT_BIT1: could not send a recessive bit
inline constexpr std::uint8_t kProtocolErrorTx = 0x80;     ///< CAN_ERR_PROT_TX: seen while transmitting
/// CAN_ERR_PROT's place, in data[3] (CAN_ERR_PROT_LOC_*).
inline constexpr std::uint8_t kProtocolLocationUnspecified = 0x00;
inline constexpr std::uint8_t kProtocolLocationSof = 0x03;
inline constexpr std::uint8_t kProtocolLocationId28To21 = 0x02;
inline constexpr std::uint8_t kProtocolLocationId20To18 = 0x06;
inline constexpr std::uint8_t kProtocolLocationSrtr = 0x04;
inline constexpr std::uint8_t kProtocolLocationIde = 0x05;
inline constexpr std::uint8_t kProtocolLocationId17To13 = 0x07;
inline constexpr std::uint8_t kProtocolLocationId12To05 = 0x0F;
inline constexpr std::uint8_t kProtocolLocationId04To00 = 0x0E;
inline constexpr std::uint8_t kProtocolLocationRtr = 0x0C;
inline constexpr std::uint8_t kProtocolLocationRes1 = 0x0D;
inline constexpr std::uint8_t kProtocolLocationRes0 = 0x09;
inline constexpr std::uint8_t kProtocolLocationDlc = 0x0B;
inline constexpr std::uint8_t kProtocolLocationData = 0x0A;
inline constexpr std::uint8_t kProtocolLocationCrc = 0x08;  ///< CAN_ERR_PROT_LOC_CRC_SEQ
inline constexpr std::uint8_t kProtocolLocationCrcDelimiter = 0x18;
inline constexpr std::uint8_t kProtocolLocationAck = 0x19;
inline constexpr std::uint8_t kProtocolLocationAckDelimiter = 0x1B;
inline constexpr std::uint8_t kProtocolLocationEof = 0x1A;
inline constexpr std::uint8_t kProtocolLocationIntermission = 0x12;

/// A controller's state as Linux has it (can_state, linux/can/netlink.h;
/// `ip -details link` prints it), worse is larger.
enum class ControllerState : std::uint8_t { kErrorActive, kErrorWarning, kErrorPassive, kBusOff };
/// "error-active", "error-warning", "error-passive" or "bus-off".
constexpr const char* state_name(ControllerState state) noexcept {
  switch (state) {
    case ControllerState::kErrorActive:
      return "error-active";
    case ControllerState::kErrorWarning:
      return "error-warning";
    case ControllerState::kErrorPassive:
      return "error-passive";
    case ControllerState::kBusOff:
      return "bus-off";
  }
  return "?";
}

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
