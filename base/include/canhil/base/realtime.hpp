// canhil/base/realtime.hpp — a whole process at a real-time priority with its
// memory locked, where the system allows it (root or CAP_SYS_NICE): what the
// user-space bus's broker and the reference handler ask for. (The emulator's
// node threads ask per thread: emulator/fifo_scheduling.hpp.)
#pragma once

#include <sched.h>
#include <sys/mman.h>

#include <cerrno>

namespace canhil {

/// What a process got.
struct RealtimeGot {
  int priority = 0;            ///< its SCHED_FIFO priority; 0: the normal scheduler
  bool memory_locked = false;  ///< mlockall(MCL_CURRENT | MCL_FUTURE) held
  int refused = 0;             ///< the errno of a refused SCHED_FIFO, else 0
};

/// Asks SCHED_FIFO at `priority` for the calling process and, once it has
/// it, its memory locked; nothing for a priority of 0 or less. What the
/// system refuses is left as it was, and said in the answer.
inline RealtimeGot take_realtime(int priority) noexcept {
  RealtimeGot got;
  if (priority <= 0) return got;
  sched_param p{};
  p.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &p) != 0) {
    got.refused = errno;
    return got;
  }
  got.priority = priority;
  got.memory_locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
  return got;
}

}  // namespace canhil
