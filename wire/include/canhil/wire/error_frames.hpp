// canhil/wire/error_frames.hpp — a controller's errors and changes of state
// as Linux's CAN drivers report them: an error frame (linux/can/error.h).
//
// Classes in the id (CAN_ERR_PROT | CAN_ERR_BUSERROR for a protocol error,
// CAN_ERR_ACK for a missing acknowledgement, CAN_ERR_CRTL for a change to
// warning, passive or back to active, CAN_ERR_BUSOFF, CAN_ERR_RESTARTED),
// the protocol error's kind in data[2] and place in data[3], the controller's
// state in data[1] as can_change_state() (drivers/net/can/dev/dev.c) fills
// it (the transmit side's bits when its state is the worse or equal one, the
// receive side's likewise), and, with CAN_ERR_CNT, the transmit and receive
// error counters in data[6] and data[7]. Pure.
#pragma once

#include <cstdint>

#include "canhil/frames/frame.hpp"
#include "canhil/wire/confinement.hpp"

namespace canhil::wire {

/// The error frame for `classes` (CAN_ERR_*; 0 for a change of state alone)
/// with protocol `kind` and `location` (data[2], data[3]), the controller as
/// it is now, and a change of state when `reported` (the state last told)
/// differs from its state.
frames::CanFrame error_frame(std::uint32_t classes, std::uint8_t kind, std::uint8_t location, const Confinement& now,
                             ControllerState reported) noexcept;

}  // namespace canhil::wire
