// app/stop_signals.hpp — how a long-running command is asked to stop: Ctrl-C
// (SIGINT), SIGTERM, and SIGPIPE, the reader of its output gone
// (`canhil run | head`, a pager closed). All three set one flag, g_stop, that
// the command's loops watch, so that the command ends the way Ctrl-C ends it
// and what it set up on the machine (the RTDB's shared memory, its frame
// semaphores, the control socket) is removed; main() then ends a command
// stopped by SIGPIPE by SIGPIPE, so that the shell sees what it expects
// (exit status 141).
#pragma once

#include <atomic>

namespace canhil::app {

/// Set by SIGINT, SIGTERM and SIGPIPE once stop_on_signals() has run: the
/// one stop flag of the process's command.
extern std::atomic<bool> g_stop;

/// From here on, SIGINT, SIGTERM and SIGPIPE set g_stop. A process started
/// from the command afterwards gets the default action for all three (exec
/// resets caught signals).
void stop_on_signals();

/// After the command has returned (its objects destroyed, its tables
/// removed): a command stopped by SIGPIPE ends the process by SIGPIPE, its
/// output flushed first. Returns only if there was none.
void end_by_sigpipe_if_seen();

}  // namespace canhil::app
