// canhil/wire/confinement.hpp — one CAN controller's fault confinement: its
// transmit and receive error counters and the state they put it in.
//
// The rules are ISO 11898-1:2015's fault confinement (clause 12.1.4; Bosch
// CAN 2.0 part B section 8 says the same), numbered here as the standard
// numbers them:
//   1  a receiver detects an error: REC + 1 (not for a bit error while it
//      sends an active error flag or an overload flag)
//   2  a receiver sees a dominant bit as the first bit after its own error
//      flag: REC + 8
//   3  a transmitter sends an error flag: TEC + 8, except (a) an
//      error-passive transmitter's ACK error that meets no dominant bit
//      during its passive error flag, and (b) a stuff error in arbitration,
//      on a stuff bit sent recessive and read dominant
//   4  a transmitter's bit error while it sends an active error or overload
//      flag: TEC + 8
//   5  a receiver's bit error while it sends an active error or overload
//      flag: REC + 8
//   6  after the 7 dominant bits tolerated after a flag, each further 8:
//      TEC + 8 for a transmitter, REC + 8 for a receiver
//   7  a successful transmission: TEC - 1 (not below 0)
//   8  a successful reception: REC - 1 when 1..127; above 127, set to a value
//      from 119 to 127 (canhil: 119)
// States: error-active while both counters are at most 127, error-passive
// when one is 128 or more, bus-off when TEC passes 255; from bus-off back to
// error-active, both counters 0, after 128 occurrences of 11 consecutive
// recessive bits. Linux's view adds error-warning at 96 (CAN_ERROR_WARNING_THRESHOLD
// in linux/can/error.h; can_state_err_to_state in drivers/net/can/dev/dev.c).
//
// A value type; no clock, no bus: the bus model (wire_bus.hpp) says what
// happened, in order.
#pragma once

#include <cstdint>

#include "canhil/frames/frame.hpp"

namespace canhil::wire {

/// As Linux's can_state, in its order (worse is larger).
using frames::ControllerState;
using frames::state_name;

inline constexpr std::uint16_t kWarningLimit = 96;               // CAN_ERROR_WARNING_THRESHOLD
inline constexpr std::uint16_t kPassiveLimit = 128;              // CAN_ERROR_PASSIVE_THRESHOLD
inline constexpr std::uint16_t kBusOffLimit = 256;               // CAN_BUS_OFF_THRESHOLD
inline constexpr std::uint16_t kRecAfterPassiveReception = 119;  // rule 8: 119..127
/// Occurrences of 11 consecutive recessive bits that take a controller out of bus-off.
inline constexpr std::uint32_t kRecoveryOccurrences = 128;
inline constexpr std::uint32_t kRecoveryRunBits = 11;

/// A transmitter's error, for rule 3's exceptions.
enum class TransmitError : std::uint8_t {
  kOther,               ///< bit, form, CRC-seen-by-others or stuff error: + 8
  kAckNoDominant,       ///< no acknowledgement, and no dominant bit during the error flag
  kStuffInArbitration,  ///< a recessive stuff bit read dominant in arbitration
};

class Confinement {
 public:
  std::uint16_t tec() const noexcept { return tec_; }
  std::uint16_t rec() const noexcept { return rec_; }
  /// The controller's state: from the counters, except that bus-off stays
  /// until recovered() whatever the counters.
  ControllerState state() const noexcept {
    if (!bus_off_ && tec_ < kWarningLimit && rec_ < kWarningLimit) return ControllerState::kErrorActive;  // as a rule
    return counted_state();
  }
  /// Linux's split view (can_state_get_by_berr_counter): each counter's own state.
  ControllerState tx_state() const noexcept;
  ControllerState rx_state() const noexcept;
  bool bus_off() const noexcept { return bus_off_; }

  /// Rule 3 (and 4: `kOther`). May take the controller bus-off.
  void transmit_error(TransmitError kind) noexcept;
  /// Rule 1, or rule 2 / 5 when `plus_eight`.
  void receive_error(bool plus_eight = false) noexcept;
  /// Rule 6: one more sequence of 8 dominant bits, as a transmitter or a receiver.
  void dominant_sequence(bool transmitter) noexcept;
  /// Rule 7.
  void transmitted() noexcept {
    if (!bus_off_ && tec_ > 0) --tec_;
  }
  /// Rule 8.
  void received() noexcept {
    if (bus_off_) return;
    if (rec_ >= kPassiveLimit) {
      rec_ = kRecAfterPassiveReception;
    } else if (rec_ > 0) {
      --rec_;
    }
  }
  /// Bus-off left after the 128 occurrences of 11 recessive bits: counters 0, error-active.
  void recovered() noexcept;
  /// Sets the transmit error counter (a fault forcing bus-off: 256).
  void force_tec(std::uint16_t tec) noexcept;

 private:
  ControllerState counted_state() const noexcept;
  void check_bus_off() noexcept {
    if (tec_ >= kBusOffLimit) bus_off_ = true;
  }
  std::uint16_t tec_ = 0;
  std::uint16_t rec_ = 0;
  bool bus_off_ = false;
};

}  // namespace canhil::wire
