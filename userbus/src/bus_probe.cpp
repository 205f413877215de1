// How late the bus delivers (bus.hpp, probe_delivery): two processes speak
// the bus's own records to its broker, as the preload does for a program,
// one sending, one receiving at SCHED_FIFO as canhil's nodes do.
#include <linux/can.h>
#include <sched.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bus_internal.hpp"
#include "canhil/userbus/bus.hpp"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {
namespace {

std::int64_t realtime_ns() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

// An awake reader polls this long at most, then sleeps in recv: a frame
// that never comes costs no more.
constexpr std::int64_t kAwakeAtMostNs = 20'000'000;
// It wakes this long before the next frame could be written: more than its
// own wake-up can take (a virtual machine's timer wake-up at SCHED_FIFO:
// p99 up to 180 us), so that it is awake when the frame ends (the write's
// wire time later) and what it measures is the bus's lateness, not its own.
constexpr std::int64_t kAwakeEarlyNs = 250'000;

/// A connection to the broker that is a socket bound to `ifindex`; -1 when none.
int open_bound(const BusPaths& paths, State& state, std::int32_t ifindex) {
  const int fd = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(sa_family_t)) != 0) return -1;
  std::strncpy(a.sun_path, paths.socket.c_str(), sizeof a.sun_path - 1);
  const Hello h{kHelloSocket, static_cast<std::int32_t>(getpid())};
  Welcome w{-EIO};
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || send(fd, &h, sizeof h, 0) != sizeof h ||
      recv(fd, &w, sizeof w, 0) != sizeof w || w.slot < 0) {
    close(fd);
    return -1;
  }
  Socket& s = state.sockets[w.slot];
  s.lock.lock();
  s.seq.fetch_add(1, std::memory_order_acq_rel);
  s.ifindex = ifindex;
  s.bound = 1;
  s.seq.fetch_add(1, std::memory_order_release);
  s.lock.unlock();
  return fd;
}

// The `q` quantile of `v` (0 when empty).
double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace

DeliveryProbe probe_delivery(const BusPaths& paths, const std::string& name, int frames, int interval_us,
                             ProbeReader reader) {
  auto mapped = require_state(paths);
  State& state = mapped->state();
  const Interface* iface = find_interface(state, name.c_str());
  if (iface == nullptr) throw BusError("the bus has no interface " + name);
  const std::int32_t ifindex = iface->index;
  const int rx = open_bound(paths, state, ifindex);
  if (rx < 0) throw BusError("the probe cannot open a socket on " + name + ": " + std::strerror(errno));
  sched_param p{};
  p.sched_priority = 40;  // as canhil's emulated nodes; refused without the right: the normal scheduler
  const bool fifo = sched_setscheduler(0, SCHED_FIFO, &p) == 0;
  const pid_t sender = fork();
  if (sender < 0) throw BusError(std::string("the probe cannot fork: ") + std::strerror(errno));
  if (sender == 0) {
    const int tx = open_bound(paths, state, ifindex);
    usleep(50'000);  // the receiver's controller on the wire first
    for (int k = 0; k < frames && tx >= 0; ++k) {
      TxRecord r{};
      r.ifindex = ifindex;
      r.size = CAN_MTU;
      can_frame f{};
      f.can_id = 0x100;
      f.len = 8;
      const std::int64_t now = realtime_ns();
      std::memcpy(f.data, &now, sizeof now);
      std::memcpy(r.frame, &f, sizeof f);
      if (send(tx, &r, kTxHeader + CAN_MTU, 0) < 0) break;
      usleep(static_cast<useconds_t>(interval_us));
    }
    usleep(20'000);
    _exit(0);
  }
  DeliveryProbe out;
  out.fifo = fifo;
  std::vector<double> after_write, after_stamp;
  timeval limit{1, 0};
  setsockopt(rx, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  std::int64_t last_stamp = 0;
  for (int k = 0; k < frames; ++k) {
    RxRecord r{};
    ssize_t got = -1;
    if (reader == ProbeReader::kAwake && out.last_written != 0) {
      // Asleep until shortly before the next frame could be written (the
      // sender sleeps interval_us after each), then polling: awake when it is due.
      const std::int64_t next = out.last_written + std::int64_t{interval_us} * 1000 - kAwakeEarlyNs;
      const timespec at{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
      while (clock_nanosleep(CLOCK_REALTIME, TIMER_ABSTIME, &at, nullptr) == EINTR) {
      }
      for (const std::int64_t until = realtime_ns() + kAwakeAtMostNs; got < 0 && realtime_ns() < until;)
        got = recv(rx, &r, sizeof r, MSG_DONTWAIT);
    }
    if (got < 0) got = recv(rx, &r, sizeof r, 0);
    if (got <= 0) break;
    const std::int64_t now = realtime_ns();
    if (r.error != 0 || r.size != CAN_MTU) continue;
    std::int64_t written = 0;
    std::memcpy(&written, r.frame + offsetof(can_frame, data), sizeof written);
    after_write.push_back(static_cast<double>(now - written) / 1000.0);
    after_stamp.push_back(static_cast<double>(now - r.stamp_ns) / 1000.0);
    if (r.stamp_ns < last_stamp || written < out.last_written) ++out.out_of_order;
    last_stamp = r.stamp_ns;
    out.last_written = written;
  }
  close(rx);
  int status = 0;
  kill(sender, SIGTERM);
  waitpid(sender, &status, 0);
  p.sched_priority = 0;
  if (fifo) sched_setscheduler(0, SCHED_OTHER, &p);
  out.received = static_cast<int>(after_write.size());
  out.after_write_p50_us = percentile(after_write, 0.5);
  out.after_write_p99_us = percentile(after_write, 0.99);
  out.after_stamp_p50_us = percentile(after_stamp, 0.5);
  out.after_stamp_p99_us = percentile(after_stamp, 0.99);
  return out;
}

WakeupProbe probe_wakeup(int wakeups, int interval_us, int priority) {
  sched_param p{};
  p.sched_priority = priority;
  WakeupProbe out;
  out.fifo = sched_setscheduler(0, SCHED_FIFO, &p) == 0;
  out.priority = priority;
  std::vector<double> late;
  late.reserve(static_cast<std::size_t>(std::max(wakeups, 0)));
  timespec at{};
  clock_gettime(CLOCK_MONOTONIC, &at);
  for (int k = 0; k < wakeups; ++k) {
    at.tv_nsec += static_cast<long>(interval_us) * 1000;
    while (at.tv_nsec >= 1'000'000'000) {
      at.tv_nsec -= 1'000'000'000;
      ++at.tv_sec;
    }
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
    }
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    late.push_back(static_cast<double>((now.tv_sec - at.tv_sec) * 1'000'000'000 + (now.tv_nsec - at.tv_nsec)) / 1000.0);
  }
  p.sched_priority = 0;
  if (out.fifo) sched_setscheduler(0, SCHED_OTHER, &p);
  out.p50_us = percentile(late, 0.5);
  out.p99_us = percentile(late, 0.99);
  return out;
}

BusProbe probe_bus(int frames, int interval_us, std::uint32_t bit_rate) {
  char folder[] = "/tmp/canhil-probe-bus-XXXXXX";
  if (mkdtemp(folder) == nullptr) throw BusError(std::string("no folder for a probe's bus: ") + std::strerror(errno));
  const char* before = std::getenv("CANHIL_BUS_DIR");
  const std::string kept = before != nullptr ? before : "";
  setenv("CANHIL_BUS_DIR", folder, 1);
  const BusPaths paths = BusPaths::current();
  BrokerOptions options;
  options.owner = getpid();
  start_broker(paths, options);
  add_interfaces(paths, {"vcan0"});
  BusProbe out;
  out.instant = probe_delivery(paths, "vcan0", frames, interval_us);
  LinkSettings link;
  link.bit_rate = bit_rate;
  set_link(paths, "vcan0", link);
  out.timed = probe_delivery(paths, "vcan0", frames, interval_us);
  out.timed_awake = probe_delivery(paths, "vcan0", frames, interval_us, ProbeReader::kAwake);
  stop_broker(paths);
  out.machine = probe_wakeup(frames, interval_us, BrokerOptions{}.rt_priority);
  std::filesystem::remove_all(folder);
  if (before != nullptr) {
    setenv("CANHIL_BUS_DIR", kept.c_str(), 1);
  } else {
    unsetenv("CANHIL_BUS_DIR");
  }
  return out;
}

}  // namespace canhil::userbus
