// What bus.cpp and bus_link.cpp share: the broker's control requests and the
// mapped state of a bus that must be running. Private to canhil::userbus.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "canhil/userbus/bus.hpp"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {

/// One control request to the running broker; its answer (0 or -errno).
int ask_broker(const BusPaths& paths, const ControlRequest& request);
int ask_broker(const BusPaths& paths, std::uint32_t op);

/// The running bus's state; BusError saying what to do when none runs.
std::unique_ptr<MappedState> require_state(const BusPaths& paths);

/// Process `pid`'s program as /proc/PID/comm says, or "?".
std::string program_of(int pid);

/// An interface's wire for `canhil bus list`: its rates, restart delay,
/// transmit queue, load and error frames, or that it has none.
std::string wire_text(const Interface& i);
/// One line per controller on a timed interface.
std::string controllers_text(const BusPaths& paths);

}  // namespace canhil::userbus
