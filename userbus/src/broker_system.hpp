// What the broker asks of the system: its own scheduling (taken with
// canhil::take_realtime, base/realtime.hpp; switched here), and room in a
// receiver's buffer (whether a receiver that has not read is waiting for a
// CPU or the disk, or for something else: canhil::process_held_by_machine,
// base/process.hpp).
#pragma once

#include <sys/epoll.h>
#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <string>

namespace canhil::userbus {

struct State;

/// Back to the normal scheduler (`fifo` false) or to SCHED_FIFO at
/// `priority` (true), for the calling process.
void set_fifo(bool fifo, int priority);

/// "SCHED_FIFO 45, memory locked", or "normal scheduler" (State's record).
std::string scheduling_text(const State& s);

/// Waits for room in a full receiver's buffer (the broker's end `fd` of its
/// connection, its process `pid`, the records it has read so far `taken`:
/// Socket::taken, which the preload counts); true once there is some (the
/// kernel's AF_UNIX rule: once the receiver has read three quarters of what
/// its buffer held), or once the connection ends (its end is read next). The
/// receiver has `grace_us` to read; each record it reads renews the grace;
/// while one of its threads is runnable but not running (a busy machine) or
/// in an uninterruptible wait (a write to a busy disk: candump -l), it is held
/// by the machine, and the grace starts again; `patience_us` bounds the wait
/// in all. False for a receiver that read nothing for the grace while it
/// could have (stuck), or past the patience; at once for a grace of 0 (the
/// kernel's immediate drop). Reads the monotonic clock past any time shim.
bool room_came(int fd, pid_t pid, const std::atomic<std::uint64_t>& taken, std::uint32_t grace_us,
               std::uint32_t patience_us);

/// Whether a process still runs, watched through a pidfd, which says so once
/// it has ended even before it is reaped and cannot be taken for a later
/// process of the same pid; else (no pidfd: before Linux 5.3, or a seccomp
/// profile refusing it) by kill(pid, 0).
class PidWatch {
 public:
  PidWatch() = default;
  ~PidWatch();
  PidWatch(const PidWatch&) = delete;
  PidWatch& operator=(const PidWatch&) = delete;
  /// Whether `pid` runs (watching it from now on, if it was another).
  bool alive(pid_t pid);

 private:
  pid_t pid_ = 0;
  int fd_ = -1;
  bool gone_ = true;
};

/// The spin a lockstep run asks of the broker (State::spin).
class Spin {
 public:
  explicit Spin(State& state) : state_(state) {}
  /// What arrives on `epoll` within the spin asked for, looked for while
  /// giving way to any other runnable thread: epoll_wait's answer, 0 when
  /// nothing came or no living run asks. At SCHED_FIFO, sched_yield gives
  /// way to no normal process: the broker looks on at the normal scheduler,
  /// and is real-time again once no run asks.
  int look(int epoll, epoll_event* events, int max);

 private:
  State& state_;
  PidWatch asker_;
  bool fifo_ = true;  // at its SCHED_FIFO priority now (when it has one: State::rt_priority)
};

/// The timer of the broker's timed interfaces: a timerfd on the real
/// monotonic clock (a raw system call, past any time shim), one shot, set a
/// lead before the wire's next event, so that the frame is handed over at
/// its end of frame, not a wake-up later; the rest is looked on for. The
/// lead is what a wake-up costs here, learnt: the latest of the last 128 to
/// 256 wake-ups, and 10 us, within 60 us (where idle cores halt, a virtual
/// machine's) and 300 us (a busy virtual machine's tail: the look costs a
/// core that long a frame at most).
class WireTimer {
 public:
  static constexpr std::int64_t kLeastLead = 60'000;
  static constexpr std::int64_t kMostLead = 300'000;
  WireTimer();
  ~WireTimer();
  WireTimer(const WireTimer&) = delete;
  WireTimer& operator=(const WireTimer&) = delete;
  int fd() const noexcept { return fd_; }
  /// Set for `due` (monotonic ns; INT64_MAX: none), when that changed.
  void arm(std::int64_t due);
  /// It fired (read, spent): returns once the monotonic clock reads `due`
  /// when that is at most the lead away.
  void fired(std::int64_t due);
  std::int64_t lead() const noexcept { return lead_; }
  /// A wake-up `late` ns after the time it was set for: the lead follows.
  void learn(std::int64_t late) noexcept;

 private:
  static constexpr int kWindow = 128;
  int fd_ = -1;
  std::int64_t armed_ = INT64_MAX;  // its due time, INT64_MAX: disarmed
  std::int64_t set_for_ = 0;        // when it fires: due less the lead
  std::int64_t lead_ = kLeastLead;
  std::int64_t latest_ = 0, latest_before_ = 0;  // the latest wake-up of this window of kWindow, and the last one's
  int in_window_ = 0;
};

}  // namespace canhil::userbus
