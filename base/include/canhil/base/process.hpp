// canhil/base/process.hpp — whether a process is there, for the leftovers a
// process leaves when it is killed outright (a claim of RTDB keys, a worker's
// bus folder) and for whoever must end with its owner (a bus's broker).
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <cerrno>

namespace canhil {

/// Whether process `pid` is there: answering signal 0, or there and not ours
/// to signal (EPERM). A pid of 0 or less is nobody.
inline bool process_alive(pid_t pid) noexcept { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

}  // namespace canhil
