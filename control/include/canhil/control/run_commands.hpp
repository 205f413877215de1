// canhil/control/run_commands.hpp — the commands of a virtual-time run's
// clock, on top of the session's (commands.hpp):
//
//   pause                       virtual time stops at the next elementary cycle
//   resume
//   step [count]                when paused: advance count ECs (default 1)
//   speed {factor}              0: as fast as possible; else virtual seconds per wall second
//   run_state                   {paused, speed}
#pragma once

#include "canhil/control/commands.hpp"
#include "canhil/emulator/run_control.hpp"

namespace canhil::control {

/// Adds them to `commands`; `control` must outlive it.
void add_run_commands(Commands& commands, emulator::RunControl& control);

}  // namespace canhil::control
