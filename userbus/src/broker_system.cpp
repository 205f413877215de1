// What the broker asks of the system (broker_system.hpp).
#include "broker_system.hpp"

#include <poll.h>
#include <sched.h>
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
      if (now >= give_up || !process_runnable(pid)) return false;
      until = std::min(now + grace_ns, give_up);
    }
    pollfd p{fd, POLLOUT, 0};
    const std::int64_t wait_ns = std::min(until - now, kLook_ns);
    const int r = poll(&p, 1, static_cast<int>((wait_ns + 999999) / 1000000));
    if (r > 0) return true;
    if (r < 0 && errno != EINTR) return false;
  }
}

}  // namespace canhil::userbus
