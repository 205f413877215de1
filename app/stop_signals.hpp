// app/stop_signals.hpp — how a long-running command is asked to stop: Ctrl-C
// (SIGINT), SIGTERM, and SIGPIPE, the reader of its output gone
// (`canhil run | head`, a pager closed). All three end the command through
// its own stop flag, the way Ctrl-C does, so that what it set up on the
// machine (the RTDB's shared memory, its frame semaphores, the control
// socket) is removed; main() then ends a command stopped by SIGPIPE by
// SIGPIPE, so that the shell sees what it expects (exit status 141).
#pragma once

namespace canhil::app {

/// `stop` (async-signal-safe: it sets the command's flag) for SIGINT, SIGTERM
/// and SIGPIPE. A process started from the command afterwards gets the
/// default action for all three (exec resets caught signals).
void stop_on_signals(void (*stop)(int));

/// After the command has returned (its objects destroyed, its tables
/// removed): a command stopped by SIGPIPE ends the process by SIGPIPE.
/// Returns only if there was none.
void end_by_sigpipe_if_seen();

}  // namespace canhil::app
