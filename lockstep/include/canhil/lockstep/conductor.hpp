// canhil/lockstep/conductor.hpp — canhil's side of virtual time with external
// processes: it owns the board (board.hpp) the time shim in each process
// reads its clock from, moves the virtual time, tells the processes when
// something changed, and waits until every one of them is quiet again.
//
// A run goes: start the processes with environment() (or tell the user to),
// wait_attached(), then at each instant: set_time(now) (bumps the epoch only
// when a process's wake-up has come), after sending frames or signals
// nudge(), then wait_quiet() before the next instant; next_wakeup() says when
// the earliest sleeping process wants to run.
//
// Thread-compatible: one thread drives a Conductor.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "canhil/lockstep/board.hpp"

namespace canhil::lockstep {

using Nanos = std::chrono::nanoseconds;

/// The machine's CLOCK_MONOTONIC by the system call itself: real even in a
/// canhil whose own clocks follow the board (the shim preloaded into it).
Nanos wall_clock() noexcept;
/// User and system CPU time of process `pid` (its /proc stat, in the
/// kernel's ticks), or nothing when it cannot be read (the process is gone).
std::optional<Nanos> cpu_time_of(int pid);

struct ConductorOptions {
  /// How long (wall time) a process may take to become quiet before the run
  /// names it and stops, when it is not computing: blocked on something
  /// canhil will never give, or gone silent.
  Nanos answer_limit = std::chrono::seconds(1);
  /// How long a wait goes on while the processes are computing (their CPU
  /// time grows by at least a tenth of the wall time that passes: a team's
  /// agent building its maps at start, a slow first cycle): a process busy on
  /// the CPU is not one that stopped answering, but one that computes for
  /// longer than this is named as hung in a loop.
  Nanos busy_limit = std::chrono::seconds(60);
  /// How long canhil looks for what it waits for (the processes quiet, a
  /// frame on its sockets) before it sleeps, giving way to any other runnable
  /// thread while it looks. The answer usually comes within tens of
  /// microseconds, and where an idle core halts (a virtual machine's) waking
  /// from a sleep costs about as much again. 0: it sleeps at once.
  Nanos spin = std::chrono::microseconds(50);
  /// CLOCK_REALTIME at virtual 0 (gettimeofday, time): 2026-01-01 00:00:00 UTC,
  /// the same in every run so that what the processes print is the same.
  std::int64_t realtime_base_ns = 1'767'225'600LL * 1'000'000'000;
  /// CLOCK_MONOTONIC at virtual 0.
  std::int64_t monotonic_base_ns = 1'000LL * 1'000'000'000;
};

/// One external process (its threads summed), for the run's summary.
struct ProcessReport {
  std::string name;
  int pid = 0;
  int threads = 0;
  bool gone = false;         ///< it exited (or was killed)
  std::uint64_t blocks = 0;  ///< times one of its threads waited
  std::uint64_t frames_sent = 0;
  Nanos busy_wall{0};  ///< wall time its threads ran while canhil waited for them
};

class Conductor {
 public:
  /// Creates the board (a POSIX shared-memory object named after this
  /// process). SetupError: no shared memory.
  explicit Conductor(ConductorOptions options = {});
  ~Conductor();
  Conductor(const Conductor&) = delete;
  Conductor& operator=(const Conductor&) = delete;

  /// The board's name: the value of CANHIL_LOCKSTEP for the processes.
  const std::string& board_name() const noexcept { return name_; }
  /// The environment entries a process needs: CANHIL_LOCKSTEP and LD_PRELOAD
  /// (the shim first, then whatever `preload_already` holds).
  std::vector<std::string> environment(const std::filesystem::path& shim, const char* preload_already) const;

  /// Waits (wall time, up to `limit`) until `count` processes have attached
  /// (a process's threads count once); returns how many did.
  std::size_t wait_attached(std::size_t count, Nanos limit);

  /// Moves the virtual clock to `now` (never back). Wakes the processes if
  /// one of them asked to be woken by then.
  void set_time(Nanos now);
  Nanos now() const noexcept;
  /// Something a process may be waiting for happened: the threads whose wait
  /// it concerns check again (board.hpp's bits: kDescriptors for frames
  /// sent, kEveryChange for an activation or anything canhil cannot name),
  /// and so do those whose wake-up time has come. The others sleep on, quiet.
  void nudge(std::uint32_t what = kEveryChange);
  /// The run is over: every process stops waiting in virtual time and goes on
  /// in real time (a wait whose virtual deadline will never come ends now, so
  /// a process can take its SIGINT and exit). The destructor does it too.
  void release();
  bool released() const noexcept;
  /// Bumped by every nudge (set_time's too): a caller that saw the processes
  /// quiet at epoch E knows nothing woke them while epoch() == E.
  std::uint32_t epoch() const noexcept;
  /// The earliest virtual time a waiting process asked to be woken at.
  Nanos next_wakeup() const noexcept;

  /// Waits until every thread is quiet (waiting at the current epoch, or for
  /// a signal) and `also()` returns an empty string (canhil's own condition:
  /// the frames in flight seen, PMan's epilogues). Empty on success; after
  /// the answer limit, a sentence naming who did not answer and what canhil
  /// waited for (`waiting_for`, e.g. "the trigger message at t = 1.230 s").
  /// `limit`, when given, replaces the answer limit (a program's start may
  /// take longer than an instant). Past the limit the processes' CPU time is
  /// watched for up to 200 ms more: while it grows, the wait goes on, up to
  /// busy_limit from its start (an instant that answers in time reads none).
  /// `ready_fd`, when given, is a descriptor that becomes readable when
  /// `also()`'s answer may change (canhil's own sockets, where the frames in
  /// flight arrive): while the processes are quiet and `also()` is not
  /// satisfied, the wait is on it, not on the board, so canhil wakes as a
  /// frame arrives instead of at the next millisecond. `arrived`, when given,
  /// says from memory whether something `also()` waits for may have come
  /// (canhil's sockets on its user-space bus): the looks before sleeping ask
  /// it instead of polling `ready_fd`, a system call each look (once with no
  /// looks, ConductorOptions::spin 0), and a sleep on `ready_fd` lasts 50 us
  /// at most, since what only `arrived` tells makes nothing readable.
  std::string wait_quiet(const std::function<std::string()>& also, const std::string& waiting_for,
                         std::optional<Nanos> limit = std::nullopt, int ready_fd = -1,
                         const std::function<bool()>& arrived = {});

  /// CAN frames the processes wrote (counted by the shim), over the run.
  std::uint64_t frames_sent() const noexcept;
  /// The processes seen over the run, in the order they attached.
  std::vector<ProcessReport> processes() const;
  /// Whether this process's own clocks follow the board: canhil itself was
  /// started with the shim preloaded, so a team's library it loads (an RTDB
  /// stamping items, a PMan stamping activations) sees virtual time too.
  bool clocks_virtual_here() const noexcept { return clocks_here_; }
  /// Wall time spent in wait_quiet (canhil waiting for the processes).
  Nanos waited_wall() const noexcept { return waited_; }
  /// How wait_quiet's looks ended (ConductorOptions::spin), over the run: with
  /// something come (a change on the board, a semaphore posted, a frame on
  /// canhil's descriptor), or in a sleep. A wait may look more than once.
  std::uint64_t looks_answered() const noexcept { return looks_answered_; }
  std::uint64_t sleeps() const noexcept { return sleeps_; }

 private:
  /// Bumps the epoch and wakes the blocked threads `what` concerns (all of
  /// them when `everyone`), those whose time has come, and any running one.
  void change(std::uint32_t what, bool everyone);
  /// Whether nothing a thread blocked at epoch `seen` waits for has changed since.
  bool untouched_since(const Slot& s, std::uint32_t seen) const noexcept;
  bool quiet(std::string* who);
  bool quiet_pass(std::string* who, bool& retired);
  void sweep_dead();
  /// User and system CPU time of every process on the board, summed.
  Nanos processes_cpu() const;
  /// Whether a thread of the run is runnable (on a CPU or waiting for one).
  bool any_runnable() const;
  void retire(Slot& slot);
  /// Looks for up to ConductorOptions::spin for a change on the board since
  /// `seen`, a semaphore posted by a process, or `ready_fd` (when >= 0) to be
  /// readable: whether one came.
  bool look_briefly(std::uint32_t seen, int ready_fd, const std::function<bool()>& arrived) const;

  ConductorOptions options_;
  std::string name_;
  Board* board_ = nullptr;
  Nanos waited_{0};
  std::uint64_t looks_answered_ = 0;
  std::uint64_t sleeps_ = 0;
  bool clocks_here_ = false;
  std::uint64_t frames_of_freed_ = 0;
  /// The epoch of the last change of each kind (board.hpp's bits, by bit number).
  std::array<std::uint32_t, kChangeKinds> changed_at_{};
  std::vector<ProcessReport> freed_;  // reports of slots freed (processes gone)
};

}  // namespace canhil::lockstep
