#include "canhil/wire/error_frames.hpp"

#include <algorithm>

namespace canhil::wire {

namespace {

// can_tx_state_to_frame / can_rx_state_to_frame: warning and passive have a
// bit for each side, active one for both, bus-off none (its own class).
std::uint8_t state_bits(ControllerState state, bool tx) noexcept {
  switch (state) {
    case ControllerState::kErrorActive:
      return frames::kControllerActive;
    case ControllerState::kErrorWarning:
      return tx ? frames::kControllerTxWarning : frames::kControllerRxWarning;
    case ControllerState::kErrorPassive:
      return tx ? frames::kControllerTxPassive : frames::kControllerRxPassive;
    case ControllerState::kBusOff:
      return 0;
  }
  return 0;
}

}  // namespace

frames::CanFrame error_frame(std::uint32_t classes, std::uint8_t kind, std::uint8_t location, const Confinement& now,
                             ControllerState reported) noexcept {
  frames::CanFrame f;
  f.kind = frames::FrameKind::kError;
  f.len = frames::kMaxDataBytes;
  f.data[2] = kind;
  f.data[3] = location;
  const ControllerState state = now.state();
  if (state != reported) {
    if (state == ControllerState::kBusOff) {
      classes |= frames::kErrorClassBusOff;
    } else {
      classes |= frames::kErrorClassController;
      const ControllerState tx = now.tx_state();
      const ControllerState rx = now.rx_state();
      if (tx >= rx) f.data[1] |= state_bits(tx, true);
      if (tx <= rx) f.data[1] |= state_bits(rx, false);
    }
  }
  f.id = classes | frames::kErrorClassCounters;
  f.data[6] = static_cast<std::uint8_t>(std::min<std::uint16_t>(now.tec(), 255));
  f.data[7] = static_cast<std::uint8_t>(std::min<std::uint16_t>(now.rec(), 255));
  return f;
}

}  // namespace canhil::wire
