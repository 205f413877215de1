#include "canhil/wire/confinement.hpp"

#include <algorithm>

#include "bit_counts.hpp"

namespace canhil::wire {
namespace {

// can_state_err_to_state, drivers/net/can/dev/dev.c.
ControllerState by_counter(std::uint16_t counter) noexcept {
  if (counter < kWarningLimit) return ControllerState::kErrorActive;
  if (counter < kPassiveLimit) return ControllerState::kErrorWarning;
  if (counter < kBusOffLimit) return ControllerState::kErrorPassive;
  return ControllerState::kBusOff;
}

}  // namespace

ControllerState Confinement::counted_state() const noexcept {
  if (bus_off_) return ControllerState::kBusOff;
  return std::max(tx_state(), rx_state());
}

ControllerState Confinement::tx_state() const noexcept {
  return bus_off_ ? ControllerState::kBusOff : by_counter(tec_);
}

ControllerState Confinement::rx_state() const noexcept {
  return std::min(by_counter(rec_), ControllerState::kErrorPassive);
}

void Confinement::transmit_error(TransmitError kind) noexcept {
  if (bus_off_) return;
  if (kind == TransmitError::kStuffInArbitration) return;  // rule 3, exception b
  if (kind == TransmitError::kAckNoDominant && state() == ControllerState::kErrorPassive) return;  // exception a
  tec_ = static_cast<std::uint16_t>(tec_ + 8);
  check_bus_off();
}

void Confinement::receive_error(bool plus_eight) noexcept {
  if (bus_off_) return;
  rec_ = std::min<std::uint16_t>(static_cast<std::uint16_t>(rec_ + (plus_eight ? 8 : 1)), bit_counts::kRecCeiling);
}

void Confinement::dominant_sequence(bool transmitter) noexcept {
  if (transmitter) {
    transmit_error(TransmitError::kOther);
  } else {
    receive_error(true);
  }
}

void Confinement::recovered() noexcept {
  tec_ = 0;
  rec_ = 0;
  bus_off_ = false;
}

void Confinement::force_tec(std::uint16_t tec) noexcept {
  tec_ = tec;
  check_bus_off();
}

}  // namespace canhil::wire
