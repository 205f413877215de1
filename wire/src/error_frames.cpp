#include "canhil/wire/error_frames.hpp"

#include <algorithm>

namespace canhil::wire {

std::uint8_t tx_state_bits(ControllerState state) noexcept {
  switch (state) {
    case ControllerState::kErrorActive:
      return frames::kControllerActive;
    case ControllerState::kErrorWarning:
      return frames::kControllerTxWarning;
    case ControllerState::kErrorPassive:
      return frames::kControllerTxPassive;
    case ControllerState::kBusOff:
      return 0;
  }
  return 0;
}

std::uint8_t rx_state_bits(ControllerState state) noexcept {
  switch (state) {
    case ControllerState::kErrorActive:
      return frames::kControllerActive;
    case ControllerState::kErrorWarning:
      return frames::kControllerRxWarning;
    case ControllerState::kErrorPassive:
      return frames::kControllerRxPassive;
    case ControllerState::kBusOff:
      return 0;
  }
  return 0;
}

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
      if (tx >= rx) f.data[1] |= tx_state_bits(tx);
      if (tx <= rx) f.data[1] |= rx_state_bits(rx);
    }
  }
  f.id = classes | frames::kErrorClassCounters;
  f.data[6] = static_cast<std::uint8_t>(std::min<std::uint16_t>(now.tec(), 255));
  f.data[7] = static_cast<std::uint8_t>(std::min<std::uint16_t>(now.rec(), 255));
  return f;
}

}  // namespace canhil::wire
