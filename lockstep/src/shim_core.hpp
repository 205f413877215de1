// The time shim's core (libcanhil-timeshim.so, preloaded into a team's
// processes): the board, this thread's slot, the virtual clock, the one
// blocking primitive every intercepted call is built on, and the emulated
// timerfds. Internal to the shim; see canhil/lockstep/board.hpp for the
// protocol and docs/lockstep.md for what is intercepted and why. The plumbing
// any preload needs (libc's calls, the spin lock, messages) is
// canhil/base/preload.hpp's.
#pragma once

#include <pthread.h>
#include <signal.h>
#include <time.h>

#include <atomic>
#include <cstdint>

#include "canhil/base/preload.hpp"
#include "canhil/lockstep/board.hpp"

namespace canhil::lockstep::shim {

inline constexpr std::int64_t kSecond = 1'000'000'000;

using preload::next_symbol;
using preload::SpinLocked;
/// Who the shim's lines on stderr are from (preload::say).
inline constexpr const char* kWho = "canhil-timeshim";

inline std::int64_t ns_of(const timespec& ts) noexcept { return ts.tv_sec * kSecond + ts.tv_nsec; }
inline timespec timespec_of(std::int64_t ns) noexcept { return timespec{ns / kSecond, ns % kSecond}; }

/// The board, or nullptr when the process runs in real time (no
/// CANHIL_LOCKSTEP, or the conductor is gone): every call is passed through.
Board* board() noexcept;
inline bool active() noexcept { return board() != nullptr; }

/// In canhil's own process (canhil_timeshim_conduct): virtual clocks, real waits.
bool conducting() noexcept;

/// Virtual time since the run's start.
std::int64_t now_ns() noexcept;
/// A clock's reading in virtual time, for the clocks that are virtual
/// (REALTIME, MONOTONIC, BOOTTIME and their variants); false for the others
/// (CPU-time clocks), which the caller passes through.
bool virtual_reading(clockid_t clock, std::int64_t& ns) noexcept;
/// A clock's absolute time as virtual time since the run's start.
std::int64_t to_virtual(clockid_t clock, std::int64_t absolute_ns) noexcept;

enum class Wait : std::uint8_t {
  kReady,        ///< ready() said the call can complete
  kTimedOut,     ///< the virtual time reached wake_at
  kInterrupted,  ///< a signal handler ran
  kDetached,     ///< the conductor is gone: do the real call
};

/// Blocks this thread in virtual time: checks ready() (without blocking),
/// and until it holds or virtual time reaches `wake_at_ns`, marks the slot
/// blocked and waits for the conductor's next change of a kind in
/// `waits_for` (board.hpp's bits: kDescriptors for a poll, kSemaphores for a
/// sem_wait, kTimeOnly for a sleep). `ready` is called with no lock held; it
/// must not block.
template <class Ready>
Wait block(const char* what, std::int64_t wake_at_ns, std::uint32_t waits_for, Ready&& ready);

/// This process changed something another thread may wait for (a sem_post):
/// the conductor passes it on before the processes count as quiet.
void post_change(std::uint32_t what) noexcept;

/// Marks this thread as waiting for a signal or for another thread only
/// (sigsuspend, pause, waitpid, pthread_join): quiet whatever the epoch,
/// since only a signal or that thread ends it; the conductor waits for what
/// it signalled by other means (PMan's epilogue), and the other thread has a
/// slot of its own.
void begin_signal_wait(const char* what) noexcept;
void end_signal_wait() noexcept;

// Emulated timerfds: an eventfd whose counter the shim raises when virtual
// time passes the timer's expiry.
bool is_timer(int fd) noexcept;
int new_timer(clockid_t clock, int flags) noexcept;  ///< the eventfd, or -1 with errno
int set_timer(int fd, int flags, const itimerspec* value, itimerspec* old) noexcept;
int get_timer(int fd, itimerspec* value) noexcept;
void forget_timer(int fd) noexcept;
/// Raises the counter of every timer that expired by now.
void fire_timers() noexcept;
/// The earliest expiry of any armed timer (kNoWake if none).
std::int64_t next_timer() noexcept;

// The blocking primitive's parts (the template above is built on them).
Slot* my_slot() noexcept;
/// A slot for a thread about to be created (so the clock waits for it from
/// its first instruction), and the new thread taking it.
Slot* claim_for_new_thread() noexcept;
void adopt(Slot* slot) noexcept;
void release(Slot* slot) noexcept;
/// pthread_create's record of a thread it started with `slot`, and
/// pthread_join's lookup of it (its thread id, once it runs; 0: unknown).
void remember_started(pthread_t thread, Slot* slot) noexcept;
std::int32_t take_started(pthread_t thread) noexcept;
/// A pthread_join: a signal wait that lasts while thread `tid` exists.
void begin_join_wait(std::int32_t tid) noexcept;
/// What a blocked slot saw before its check: its wake word, then the epoch.
struct Seen {
  std::uint32_t wake;
  std::uint32_t epoch;
};
Seen look_before_check(Slot& slot) noexcept;
Wait wait_for_change(Slot& slot, const char* what, Seen seen, std::int64_t wake_at_ns,
                     std::uint32_t waits_for) noexcept;

template <class Ready>
Wait block(const char* what, std::int64_t wake_at_ns, std::uint32_t waits_for, Ready&& ready) {
  Slot* slot = my_slot();
  if (slot == nullptr) return Wait::kDetached;
  for (;;) {
    const Seen seen = look_before_check(*slot);
    fire_timers();
    if (ready()) return Wait::kReady;
    if (now_ns() >= wake_at_ns) return Wait::kTimedOut;
    const std::int64_t timer = next_timer();
    const Wait w = wait_for_change(*slot, what, seen, timer < wake_at_ns ? timer : wake_at_ns, waits_for);
    if (w != Wait::kReady) return w;  // kReady here: something changed, check again
  }
}

}  // namespace canhil::lockstep::shim
