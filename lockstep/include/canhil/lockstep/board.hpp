// canhil/lockstep/board.hpp — the shared-memory board between canhil (the
// conductor, which owns the virtual clock) and the time shim preloaded into
// each external process (the team's handler and agent).
//
// The protocol, in one paragraph. The conductor writes the virtual time and
// then bumps `epoch` (a futex word) whenever something a blocked process may
// be waiting for can have changed: the time moved, canhil sent frames, PMan
// activated someone. Each thread of an external process has a slot. Before it
// blocks (a sleep, a poll, a blocking read, sigsuspend...) the shim reads the
// epoch, checks once without blocking whether its call can complete, and if
// not marks its slot blocked *at that epoch* with the virtual time it would
// wake at and what it waits for (descriptors, a semaphore, only the clock),
// then waits on its slot's own futex word. A change names what it concerns:
// the conductor wakes only the slots it concerns (and those whose time has
// come) and counts the others quiet at their older epoch, since nothing they
// wait for changed. So an agent waiting for its vision frame's semaphore
// sleeps through the instants whose only news is CAN frames. The conductor
// moves the clock only when every slot is quiet (blocked at the current
// epoch, or at one after the last change that concerned it) and every frame
// the processes sent has been seen on the bus. Nothing is counted in advance:
// a process that decides to send one more frame simply does not block until
// it has sent it. A process's own change to another's wait (a sem_post) is
// posted on the board; the conductor turns it into a change before the
// processes count as quiet.
//
// Layout rules: fixed-size, no pointers, lock-free atomics only (they work
// across processes in shared memory on Linux); bump kVersion on any change.
#pragma once

#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <ctime>

namespace canhil::lockstep {

inline constexpr std::uint32_t kMagic = 0x4C4B5354;  // "LKST"
inline constexpr std::uint32_t kVersion = 3;
inline constexpr std::size_t kMaxSlots = 64;
inline constexpr std::size_t kNameBytes = 32;
inline constexpr std::size_t kWhatBytes = 24;
/// wake_at_ns of a slot that waits with no timeout.
inline constexpr std::int64_t kNoWake = INT64_MAX;
/// The environment variable naming the board (a POSIX shared-memory name).
inline constexpr const char* kBoardVariable = "CANHIL_LOCKSTEP";

/// What a blocked thread waits for besides its wake-up time (Slot::waits_for),
/// and what a change concerns (Conductor::nudge): bits.
inline constexpr std::uint32_t kTimeOnly = 0;            ///< a sleep: only the clock ends it
inline constexpr std::uint32_t kDescriptors = 1U << 0;   ///< poll, select, epoll, read: a descriptor's data
inline constexpr std::uint32_t kSemaphores = 1U << 1;    ///< sem_wait, sem_timedwait: a post
inline constexpr std::uint32_t kOtherChanges = 1U << 2;  ///< what the shim cannot tell apart (a signal's arrival)
inline constexpr std::uint32_t kEveryChange = kDescriptors | kSemaphores | kOtherChanges;
inline constexpr std::size_t kChangeKinds = 3;

enum class SlotState : std::uint32_t {
  kFree = 0,
  kRunning = 1,  ///< the thread is doing something: the clock waits
  kBlocked = 2,  ///< the thread waits (at seen_epoch, until wake_at_ns or something changes)
  kGone = 3,     ///< the thread or its process ended; the conductor frees it
};

struct alignas(64) Slot {
  std::atomic<std::uint32_t> state{0};       ///< SlotState
  std::atomic<std::uint32_t> seen_epoch{0};  ///< the epoch it checked before blocking
  /// The futex word it waits on: the conductor raises it to wake this slot alone.
  std::atomic<std::uint32_t> wake{0};
  std::atomic<std::uint32_t> waits_for{kEveryChange};  ///< what ends its wait besides the clock (bits)
  /// 1 while it waits for a signal only (sigsuspend, pause, waitpid): quiet at
  /// any epoch; the conductor waits for what it signalled by other means.
  std::atomic<std::uint32_t> signal_wait{0};
  /// The thread it joins (pthread_join), while it does: quiet only as long as
  /// that thread exists (once it is gone, the joiner is about to run).
  std::atomic<std::int32_t> join_tid{0};
  std::atomic<std::int64_t> wake_at_ns{kNoWake};
  std::atomic<std::uint64_t> frames_sent{0};           ///< CAN frames it wrote (counted on success)
  std::atomic<std::uint64_t> blocks{0};                ///< times it blocked
  std::atomic<std::uint64_t> busy_wall_ns{0};          ///< wall time spent running between blocks
  std::atomic<std::int64_t> running_since_wall_ns{0};  ///< CLOCK_MONOTONIC (real) when it last ran
  std::atomic<std::int32_t> pid{0};
  std::atomic<std::int32_t> tid{0};
  char name[kNameBytes]{};  ///< the process's comm; written before state leaves kFree
  char what[kWhatBytes]{};  ///< the call it blocks in ("poll", "nanosleep", "sigsuspend", ...)
};

struct Board {
  std::uint32_t magic = 0;
  std::uint32_t version = 0;
  std::int32_t conductor_pid = 0;
  /// Set when canhil's run has ended (Conductor::release): every process
  /// stops waiting on the board and goes on in real time.
  std::atomic<std::uint32_t> released{0};
  /// CLOCK_REALTIME (and gettimeofday, time) at virtual 0; CLOCK_MONOTONIC and
  /// CLOCK_BOOTTIME read monotonic_base_ns + now.
  std::int64_t realtime_base_ns = 0;
  std::int64_t monotonic_base_ns = 0;
  alignas(64) std::atomic<std::int64_t> now_ns{0};    ///< virtual time since the run's start
  alignas(64) std::atomic<std::uint32_t> epoch{0};    ///< bumped by each change the conductor makes
  alignas(64) std::atomic<std::uint32_t> changes{0};  ///< futex word the conductor waits on: bumped on each block
  /// Changes a process made to another's wait (bits: a sem_post is kSemaphores),
  /// for the conductor to pass on; set before the process's next block.
  std::atomic<std::uint32_t> posted{0};
  alignas(64) Slot slots[kMaxSlots];
};

static_assert(std::atomic<std::int64_t>::is_always_lock_free);
static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
static_assert(sizeof(std::atomic<std::uint32_t>) == 4, "futex words are 32-bit");

/// futex(2) on a word of the board (or any 32-bit word shared between
/// processes): FUTEX_WAIT while it holds `value`, up to `timeout` (nullptr:
/// no limit), or FUTEX_WAKE of `value` waiters. The conductor, the shim and
/// the bench's bare round trip wait and wake through it.
inline long futex(std::atomic<std::uint32_t>* word, int op, std::uint32_t value,
                  const timespec* timeout = nullptr) noexcept {
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t), "a futex word is 32 bits");
  return syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word), op, value, timeout, nullptr, 0);
}

}  // namespace canhil::lockstep
