// canhil-hwcomm --iface IFACE [--dbc FILE] [--ec-ms 10] [--bit-rate 1000000] [--duration S] [--rt-priority N]
// [--busy-poll]
//               [--rtdb-lib LIB --rtdb-items RTDB_USER_H --rtdb-ini RTDB_INI] [--layout cambada|canhil|FILE]
//               [--slow-ms MS]
//
// The reference low-level communication handler: this robot's RTDB (AGENT)
// on one side, its CAN bus on the other. The RTDB is canhil's, or the team's
// own library loaded at run time (its rtdb.ini and generated rtdb_user.h),
// every item in the team's layout (cambada for a team library unless told).
// Runs until Ctrl-C (or --duration) and prints a summary, with the latency
// from each frame's kernel receive timestamp to its RTDB write. --slow-ms
// plays a slow machine: after each batch of frames it spends MS of wall time
// (by the system call itself, which canhil's time shim does not see), so that
// a lockstep run can show its outcome does not depend on the machine's speed.
#include <poll.h>
#include <sys/syscall.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>

#include "canhil/base/preload.hpp"
#include "canhil/base/realtime.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/laptop/hwcomm.hpp"
#include "canhil/laptop/raw_can.hpp"
#include "canhil/lockstep/shim_hook.h"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/layout.hpp"
#include "canhil/userbus/bus.hpp"
#include "cli_numbers.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

canhil::Nanos wall_now() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::chrono::seconds(ts.tv_sec) + canhil::Nanos(ts.tv_nsec);
}

/// Hardware in the loop: run before ordinary work and never page out, where
/// the system allows it (root or CAP_SYS_NICE). Not in a lockstep run (the
/// time shim loaded): there virtual time is the clock and a real-time
/// priority would only keep others from their turn. What it used, in words.
std::string take_rt_priority(int priority) {
  if (priority == 0) return "normal scheduler (--rt-priority 0)";
  if (canhil::preload::any_symbol<canhil_shim_frames_sent_fn>("canhil_shim_frames_sent") != nullptr)
    return "normal scheduler (virtual time: a lockstep run)";
  const canhil::RealtimeGot got = canhil::take_realtime(priority);
  if (got.priority == 0) {
    return "normal scheduler (SCHED_FIFO " + std::to_string(priority) + " refused: " + std::strerror(got.refused) +
           "; it needs root or CAP_SYS_NICE)";
  }
  return "SCHED_FIFO " + std::to_string(priority) +
         (got.memory_locked ? ", memory locked" : ", memory not locked (RLIMIT_MEMLOCK)");
}

int usage(const char* why) {
  std::fprintf(stderr,
               "canhil-hwcomm: %s\nusage: canhil-hwcomm --iface IFACE [--dbc FILE] [--ec-ms 10] [--bit-rate 1000000] "
               "[--duration S] "
               "[--rt-priority N] [--busy-poll]\n"
               "         [--rtdb-lib LIB --rtdb-items RTDB_USER_H --rtdb-ini RTDB_INI] [--layout cambada|canhil|FILE]\n"
               "         [--slow-ms MS]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  // Where the kernel has no CAN and canhil's user-space bus runs: start again on it.
  canhil::userbus::join_bus_if_needed(argv);
  std::string iface;
  std::string dbc = canhil::frames::default_dbc_path().string();
  double ec_ms = 10;
  double bit_rate = 1'000'000;  // the TM's wire time: the asynchronous window opens when it has left the wire
  double duration_s = 0;
  // Above the team's ordinary processes, below the emulated nodes (40) and the user-space bus's broker (45).
  int rt_priority = 35;
  bool busy_poll = false;
  double slow_ms = 0;
  std::string rtdb_lib, rtdb_items, rtdb_ini, layout_name;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--busy-poll") {
        busy_poll = true;
        continue;
      }
      if (i + 1 >= argc) return usage(("missing value for " + a).c_str());
      if (a == "--iface") {
        iface = argv[++i];
      } else if (a == "--dbc") {
        dbc = argv[++i];
      } else if (a == "--ec-ms") {
        ec_ms = canhil::laptop::parse_number(a, argv[++i]);
      } else if (a == "--bit-rate") {
        bit_rate = canhil::laptop::parse_number(a, argv[++i]);
        if (!(bit_rate >= 10'000 && bit_rate <= 1'000'000)) return usage("--bit-rate takes 10000..1000000 bit/s");
      } else if (a == "--duration") {
        duration_s = canhil::laptop::parse_number(a, argv[++i]);
      } else if (a == "--rtdb-lib") {
        rtdb_lib = argv[++i];
      } else if (a == "--rtdb-items") {
        rtdb_items = argv[++i];
      } else if (a == "--rtdb-ini") {
        rtdb_ini = argv[++i];
      } else if (a == "--layout") {
        layout_name = argv[++i];
      } else if (a == "--slow-ms") {
        slow_ms = canhil::laptop::parse_number(a, argv[++i]);
        if (!(slow_ms >= 0 && slow_ms <= 60'000)) return usage("--slow-ms takes 0..60000 ms");
      } else if (a == "--rt-priority") {
        rt_priority = static_cast<int>(canhil::laptop::parse_number(a, argv[++i]));
      } else {
        return usage(("unknown option " + a).c_str());
      }
    }
  } catch (const std::invalid_argument& e) {
    return usage(e.what());
  }
  if (iface.empty()) return usage("--iface is required");
  if (rtdb_lib.empty() && (!rtdb_items.empty() || !rtdb_ini.empty())) {
    return usage("--rtdb-items and --rtdb-ini describe a team library's table: give --rtdb-lib too");
  }
  if (!rtdb_lib.empty() && (rtdb_items.empty() || rtdb_ini.empty())) {
    return usage("--rtdb-lib needs the team's --rtdb-items (its generated rtdb_user.h) and --rtdb-ini");
  }
  if (layout_name.empty()) layout_name = rtdb_lib.empty() ? "canhil" : "cambada";
  if (rt_priority < 0 || rt_priority > 99) return usage("--rt-priority takes 1..99, or 0 for the normal scheduler");
  std::fputs(("canhil-hwcomm: " + take_rt_priority(rt_priority) + "\n").c_str(), stderr);
  try {
    auto set = canhil::frames::MessageSet::load(dbc);
    canhil::laptop::RawCan can(iface);
    namespace rtdb = canhil::rtdb;
    const bool shipped = layout_name == "canhil" || layout_name == "cambada";
    const rtdb::Layout layout = shipped ? rtdb::Layout::shipped(layout_name) : rtdb::Layout::load(layout_name);
    const auto db = rtdb_lib.empty() ? rtdb::open_builtin(rtdb::Scope::kOneAgent)
                                     : rtdb::open_library(rtdb_lib, rtdb::ItemTable::from_files(rtdb_items, rtdb_ini),
                                                          rtdb::Scope::kOneAgent, std::filesystem::path(rtdb_ini));
    const int agent = db->spaces().front();
    const auto ec = std::chrono::duration_cast<canhil::Nanos>(std::chrono::duration<double, std::milli>(ec_ms));
    canhil::laptop::HwComm hw(
        set, ec, [&](const canhil::frames::CanFrame& f) { return can.send(f); }, wall_now, *db, layout, agent);
    hw.set_bit_rate(static_cast<std::uint32_t>(bit_rate));
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    const int timer = timerfd_create(CLOCK_REALTIME, TFD_NONBLOCK | TFD_CLOEXEC);
    const canhil::Nanos end =
        duration_s > 0
            ? wall_now() + std::chrono::duration_cast<canhil::Nanos>(std::chrono::duration<double>(duration_s))
            : canhil::kNever;
    std::printf("canhil-hwcomm: agent %d (%s) on %s; RTDB %s, layout %s\n", agent,
                db->items().agent_name(agent).c_str(), iface.c_str(), db->library().c_str(), layout.name().c_str());
    std::fflush(stdout);
    while (!g_stop && wall_now() < end) {
      pollfd p[2] = {{can.fd(), POLLIN, 0}, {timer, POLLIN, 0}};
      const canhil::Nanos deadline = hw.next_deadline();
      timespec timeout{0, 100'000'000};
      if (deadline != canhil::kNever) {
        itimerspec spec{};
        spec.it_value.tv_sec = static_cast<time_t>(deadline.count() / 1'000'000'000);
        spec.it_value.tv_nsec = static_cast<long>(deadline.count() % 1'000'000'000);
        timerfd_settime(timer, TFD_TIMER_ABSTIME, &spec, nullptr);
      }
      if (busy_poll) {
        // Spin instead of sleeping: no wake-up latency, one core fully used.
        timeout = timespec{0, 0};
      }
      ::ppoll(p, 2, &timeout, nullptr);
      if ((p[1].revents & POLLIN) != 0) {
        std::uint64_t n = 0;
        [[maybe_unused]] const auto r = ::read(timer, &n, sizeof n);
      }
      bool got = false;
      while (auto f = can.receive()) {
        hw.on_frame(f->frame, f->time);
        got = true;
      }
      if (got && slow_ms > 0) {
        const auto ns = static_cast<long long>(slow_ms * 1e6);
        const timespec wall{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
        syscall(SYS_nanosleep, &wall, nullptr);
      }
      if (wall_now() >= hw.next_deadline()) hw.on_time(wall_now());
    }
    ::close(timer);
    std::printf("canhil-hwcomm: summary\n%s", hw.summary().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "canhil-hwcomm: %s\n", e.what());
    return 2;
  }
}
