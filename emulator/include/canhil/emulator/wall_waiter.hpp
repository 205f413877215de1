// canhil/emulator/wall_waiter.hpp — the real-time loops' wait: until an absolute
// CLOCK_REALTIME deadline (a timerfd with TFD_TIMER_ABSTIME) or until one of
// the sockets is readable, at most 100 ms so Ctrl-C is noticed.
#pragma once

#include <poll.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/base/time.hpp"

namespace canhil::emulator {

/// Waits until an absolute CLOCK_REALTIME deadline or until a socket is readable.
class WallWaiter {
 public:
  explicit WallWaiter(std::vector<int> fds) : fds_(std::move(fds)) {
    timer_ = timerfd_create(CLOCK_REALTIME, TFD_NONBLOCK | TFD_CLOEXEC);
    if (timer_ < 0) throw SetupError("timerfd_create failed");
  }
  ~WallWaiter() { ::close(timer_); }
  WallWaiter(const WallWaiter&) = delete;
  WallWaiter& operator=(const WallWaiter&) = delete;

  void wait(Nanos deadline) {
    std::vector<pollfd>& p = polled_;  // reused: no allocation per wait
    p.clear();
    for (int fd : fds_) p.push_back(pollfd{fd, POLLIN, 0});
    timespec timeout{0, 100'000'000};  // at most 100 ms, to notice Ctrl-C
    timespec* to = &timeout;
    if (deadline != kNever) {
      itimerspec spec{};
      const auto ns = deadline.count();
      spec.it_value.tv_sec = static_cast<time_t>(ns / 1'000'000'000);
      spec.it_value.tv_nsec = static_cast<long>(ns % 1'000'000'000);
      if (spec.it_value.tv_sec == 0 && spec.it_value.tv_nsec == 0) spec.it_value.tv_nsec = 1;
      timerfd_settime(timer_, TFD_TIMER_ABSTIME, &spec, nullptr);
      p.push_back(pollfd{timer_, POLLIN, 0});
      to = nullptr;
    }
    const int r = ::ppoll(p.data(), p.size(), to, nullptr);
    if (r > 0 && deadline != kNever && (p.back().revents & POLLIN) != 0) {
      std::uint64_t expirations = 0;
      [[maybe_unused]] const auto n = ::read(timer_, &expirations, sizeof expirations);
    }
  }

 private:
  std::vector<int> fds_;
  std::vector<pollfd> polled_;
  int timer_ = -1;
};

}  // namespace canhil::emulator
