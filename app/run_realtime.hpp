// app/run_realtime.hpp — `canhil run` in real time: drives a session with the
// real-time driver and reports (progress, interface state, goals, the
// summary). The run itself is emulator::RealtimeDriver.
#pragma once

#include <cstdio>
#include <optional>
#include <string>

#include "canhil/emulator/realtime_driver.hpp"

namespace canhil::app {

struct RealtimeOutput {
  emulator::RunLength length;             ///< seconds 0: until Ctrl-C (or `stop`)
  bool quiet = false;                     ///< no progress lines
  FILE* out = stdout;                     ///< where everything goes (a benchmark passes /dev/null)
  std::optional<std::string> save_world;  ///< where to save the world at the end
};

/// Runs until the duration ends or Ctrl-C; returns the exit status (130 after
/// Ctrl-C). The summary is printed before the world is saved, so a path that
/// cannot be written costs no result.
int run_realtime(emulator::Session& session, const emulator::RealtimeOptions& options, const RealtimeOutput& output);

/// Says, when the run was asked for a timed bus, whether its SocketCAN buses
/// carry it (`timed`: the user-space bus's broker runs the wire on `clock`)
/// or deliver at once (the kernel's: docs/wire.md).
void say_the_wire(std::FILE* out, const emulator::Session& session, bool timed, const char* clock);

}  // namespace canhil::app
