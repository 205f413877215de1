// What the broker asks of the system (broker_system.hpp).
#include "broker_system.hpp"

#include <poll.h>
#include <sched.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "canhil/base/preload.hpp"
#include "canhil/base/process.hpp"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {

void set_fifo(bool fifo, int priority) {
  sched_param p{};
  p.sched_priority = fifo ? priority : 0;
  sched_setscheduler(0, fifo ? SCHED_FIFO : SCHED_OTHER, &p);
}

std::string scheduling_text(const State& s) {
  if (s.rt_priority <= 0) return "normal scheduler";
  return "SCHED_FIFO " + std::to_string(s.rt_priority) + (s.memory_locked != 0 ? ", memory locked" : "");
}

bool room_came(int fd, pid_t pid, const std::atomic<std::uint64_t>& taken, std::uint32_t grace_us,
               std::uint32_t patience_us) {
  if (grace_us == 0) return false;
  constexpr std::int64_t kLook_ns = 1000000;  // how often the receiver's reads are looked at
  const std::int64_t grace_ns = static_cast<std::int64_t>(grace_us) * 1000;
  const std::int64_t start = ::canhil::preload::real_monotonic_ns();
  const std::int64_t give_up = start + std::max(grace_ns, static_cast<std::int64_t>(patience_us) * 1000);
  std::int64_t until = start + grace_ns;
  std::uint64_t read_so_far = taken.load(std::memory_order_acquire);
  for (;;) {
    const std::int64_t now = ::canhil::preload::real_monotonic_ns();
    if (const std::uint64_t read_now = taken.load(std::memory_order_acquire); read_now != read_so_far) {
      read_so_far = read_now;
      until = std::min(now + grace_ns, give_up);
    }
    if (now >= until) {
      if (now >= give_up || !process_held_by_machine(pid)) return false;
      until = std::min(now + grace_ns, give_up);
    }
    pollfd p{fd, POLLOUT, 0};
    const std::int64_t wait_ns = std::min(until - now, kLook_ns);
    const int r = poll(&p, 1, static_cast<int>((wait_ns + 999999) / 1000000));
    if (r > 0) return true;
    if (r < 0 && errno != EINTR) return false;
  }
}

PidWatch::~PidWatch() {
  if (fd_ >= 0) close(fd_);
}

bool PidWatch::alive(pid_t pid) {
  if (pid != pid_) {
    if (fd_ >= 0) close(fd_);
    pid_ = pid;
    fd_ = pid > 0 ? static_cast<int>(syscall(SYS_pidfd_open, pid, 0)) : -1;
    gone_ = pid <= 0 || (fd_ < 0 && errno == ESRCH);
  }
  if (gone_) return false;
  if (fd_ < 0) return process_alive(pid);
  pollfd p{fd_, POLLIN, 0};
  const timespec at_once{0, 0};
  gone_ = syscall(SYS_ppoll, &p, 1, &at_once, nullptr, 8) != 0;  // readable once it has ended
  return !gone_;
}

int Spin::look(int epoll, epoll_event* events, int max) {
  const std::uint64_t word = state_.spin.load(std::memory_order_acquire);
  const std::uint32_t us = spin_us(word);
  const bool asked = us != 0 && asker_.alive(spin_pid(word));
  if (state_.rt_priority > 0 && asked == fifo_) {
    fifo_ = !asked;
    set_fifo(fifo_, state_.rt_priority);
  }
  if (!asked) return 0;
  state_.spins.fetch_add(1, std::memory_order_relaxed);
  const std::int64_t until = preload::real_monotonic_ns() + static_cast<std::int64_t>(us) * 1000;
  for (;;) {
    const int n = epoll_wait(epoll, events, max, 0);
    if (n != 0 || preload::real_monotonic_ns() >= until) return n;
    sched_yield();
  }
}

WireTimer::WireTimer() {
  fd_ = static_cast<int>(syscall(SYS_timerfd_create, CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  prctl(PR_SET_TIMERSLACK, 1UL);  // a frame's end is due to the microsecond
}

WireTimer::~WireTimer() {
  if (fd_ >= 0) close(fd_);
}

void WireTimer::arm(std::int64_t due) {
  if (fd_ < 0 || due == armed_) return;
  armed_ = due;
  itimerspec t{};
  if (due != INT64_MAX) {
    const std::int64_t at = std::max<std::int64_t>(due - lead_, 1);
    set_for_ = at;
    t.it_value = {static_cast<time_t>(at / 1'000'000'000), static_cast<long>(at % 1'000'000'000)};
  }
  syscall(SYS_timerfd_settime, fd_, TFD_TIMER_ABSTIME, &t, nullptr);
}

void WireTimer::fired(std::int64_t due) {
  std::uint64_t expirations = 0;
  std::int64_t now = preload::real_monotonic_ns();
  if (read(fd_, &expirations, sizeof expirations) >= 0) {
    armed_ = INT64_MAX;  // one shot, spent
    learn(now - set_for_);
  }
  while (due - now > 0 && due - now <= lead_) now = preload::real_monotonic_ns();
}

void WireTimer::learn(std::int64_t late) noexcept {
  latest_ = std::max(latest_, late);
  if (++in_window_ == kWindow) {
    latest_before_ = latest_;
    latest_ = 0;
    in_window_ = 0;
  }
  constexpr std::int64_t kMargin = 10'000;
  lead_ = std::clamp(std::max(latest_, latest_before_) + kMargin, kLeastLead, kMostLead);
}

}  // namespace canhil::userbus
