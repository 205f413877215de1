// app/bench_external.cpp — `canhil bench --part external` (bench_external.hpp).
#include "bench_external.hpp"

#include <linux/futex.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <new>
#include <optional>

#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "canhil/lockstep/round_trip.hpp"
#include "canhil/userbus/bus.hpp"
#include "canhil/userbus/state.hpp"
#include "run_external.hpp"

namespace canhil::app {
namespace {

constexpr double kTarget = 20;  // times real time, one robot, one core
constexpr int kInProcessRuns = 3;

// Pins this thread (and what it starts) to one core for its lifetime.
class PinnedToCore {
 public:
  explicit PinnedToCore(int cpu) {
    if (cpu < 0 || sched_getaffinity(0, sizeof before_, &before_) != 0) return;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(static_cast<std::size_t>(cpu), &one);
    pinned_ = sched_setaffinity(0, sizeof one, &one) == 0;
  }
  ~PinnedToCore() {
    if (pinned_) sched_setaffinity(0, sizeof before_, &before_);
  }
  PinnedToCore(const PinnedToCore&) = delete;
  PinnedToCore& operator=(const PinnedToCore&) = delete;
  bool pinned() const noexcept { return pinned_; }

 private:
  cpu_set_t before_{};
  bool pinned_ = false;
};

constexpr int kRoundTrips = 20000;

// The user-space bus's broker, when this process runs on that bus: its pid
// (else 0) and how many times it has looked for a next frame before sleeping.
struct BrokerLook {
  pid_t pid = 0;
  std::uint64_t spins = 0;
};
BrokerLook look_at_broker() {
  const auto mapped = userbus::MappedState::open(userbus::BusPaths::current());
  if (mapped == nullptr) return {};
  return {mapped->state().broker_pid, mapped->state().spins.load()};
}

// The same scenario in-process, virtual time, everything on: its wall time.
Nanos in_process_wall(const emulator::Scenario& sc, const emulator::RunOverrides& over, double seconds,
                      const std::shared_ptr<const frames::MessageSet>& messages) {
  emulator::SessionOptions options;
  options.messages = messages;
  emulator::Session session(emulator::plan_run(sc, options, over));
  emulator::VirtualOptions virtual_options;
  virtual_options.record_trace = false;
  emulator::VirtualDriver run(session, virtual_options);
  const Nanos start = lockstep::wall_clock();
  run.run_for(from_seconds(seconds));
  return lockstep::wall_clock() - start;
}

}  // namespace

bool bench_external(const ExternalBench& bench, const std::shared_ptr<const frames::MessageSet>& messages) {
  const emulator::Scenario sc = emulator::read_scenario(emulator::shipped_scenario("one_robot.toml"));
  emulator::RunOverrides over;  // the bench's robot on its interface, with canhil's handler and agent
  over.interfaces = {bench.iface};
  over.processes = {"canhil-hwcomm --iface {iface}", "canhil-agent --pose {x},{y},{heading}"};
  emulator::SessionOptions options;
  options.messages = messages;
  options.external = true;
  const emulator::RunPlan planned = emulator::plan_run(sc, options, over);
  const PinnedToCore pin(bench.cpu);
  std::printf(
      "canhil bench: external processes: one robot on %s, %g s of virtual time each, %s: in-process, then "
      "`%s` and `%s` as processes in lockstep\n",
      bench.iface.c_str(), bench.seconds,
      pin.pinned() ? ("all on CPU " + std::to_string(bench.cpu)).c_str() : "not pinned to a core",
      planned.external.launches.at(0).command.c_str(), planned.external.launches.at(1).command.c_str());
  std::fflush(stdout);
  // The fastest of three: a run of a few tens of milliseconds, which noise
  // only ever lengthens, is the yardstick of the share below.
  Nanos in_process = in_process_wall(sc, over, bench.seconds, messages);
  for (int k = 1; k < kInProcessRuns; ++k)
    in_process = std::min(in_process, in_process_wall(sc, over, bench.seconds, messages));

  emulator::Session session(planned);
  ExternalRequest run;
  run.length = {bench.seconds, "the bench"};
  run.quiet = true;
  ExternalFigures fig;
  const BrokerLook look_before = look_at_broker();
  const pid_t broker = look_before.pid;
  const std::optional<Nanos> broker_before = broker > 0 ? lockstep::cpu_time_of(broker) : std::nullopt;
  const int status = run_external(session, run, bench.shim, bench.team_preload, &fig);
  const std::optional<Nanos> broker_after = broker > 0 ? lockstep::cpu_time_of(broker) : std::nullopt;
  const std::uint64_t spins = look_at_broker().spins - look_before.spins;
  if (status != 0 || fig.simulated < from_seconds(bench.seconds)) {
    std::printf("  external run: NOT MEASURED (canhil run --external ended with status %d at t = %.3f s)\n", status,
                to_seconds(fig.simulated));
    return false;
  }
  const double factor_in = bench.seconds / to_seconds(in_process);
  const double wall = to_seconds(fig.wall);
  const double factor = bench.seconds / wall;
  std::printf("  in-process, canhil's handler and agent:         %7.1fx real time (wall %.3f s, the fastest of %d)\n",
              factor_in, to_seconds(in_process), kInProcessRuns);
  std::printf("  external processes in lockstep:                 %7.1fx real time (wall %.3f s)  target >= %gx: %s\n",
              factor, wall, kTarget, factor >= kTarget ? "met" : "MISSED");
  std::printf("  external / in-process, in this run:             %7.2f (the share of the in-process speed kept)\n",
              factor / factor_in);
  // Where the external run's wall time went.
  const double canhil_own = wall - to_seconds(fig.waited);
  const double emulation = std::min(to_seconds(in_process), canhil_own);
  double running = 0;
  const auto share = [wall](double s) { return wall > 0 ? 100 * s / wall : 0.0; };
  std::printf("  where the external run's wall time went:\n");
  std::printf("    canhil, the emulation (the in-process run's wall): %7.3f s %3.0f %%\n", emulation, share(emulation));
  std::printf("    canhil, lockstep work (sockets, fence, trace):     %7.3f s %3.0f %%\n", canhil_own - emulation,
              share(canhil_own - emulation));
  for (const lockstep::ProcessReport& p : fig.processes) {
    const double busy = to_seconds(p.busy_wall);
    running += busy;
    std::printf("    %-16s running (its code and the shim's): %7.3f s %3.0f %%  %llu waits\n", p.name.c_str(), busy,
                share(busy), static_cast<unsigned long long>(p.blocks));
  }
  const double handover = to_seconds(fig.waited) - running;
  std::printf("    hand-overs (wake-ups, context switches):           %7.3f s %3.0f %%\n", handover, share(handover));
  std::printf(
      "      canhil's looks before sleeping, up to %.0f us each ([external] spin_us): %llu answered, %llu ended in a "
      "sleep\n",
      to_seconds(session.plan().external.conductor.spin) * 1e6, static_cast<unsigned long long>(fig.looks_answered),
      static_cast<unsigned long long>(fig.sleeps));
  if (broker_before && broker_after) {
    // Another process, on any core: every frame passes it, so its time is on
    // the path of each instant, inside the hand-overs (or, on one core with
    // canhil, inside canhil's lockstep work).
    std::printf(
        "    the bus's broker (pid %d, another process), meanwhile: %.2f s of CPU (counted in ticks of 1/%ld s)\n",
        static_cast<int>(broker), to_seconds(*broker_after - *broker_before), sysconf(_SC_CLK_TCK));
    std::printf(
        "      (its looks included) it looked for a next frame %llu times, up to %g us each ([external] "
        "bus_spin_us)\n",
        static_cast<unsigned long long>(spins), session.plan().external.bus_spin_us);
  }
  // What no lockstep can go below here: each wait of a process costs at least
  // one bare round trip between two processes.
  std::uint64_t waits = 0;
  for (const lockstep::ProcessReport& p : fig.processes) waits += p.blocks;
  if (const auto trip = lockstep::bare_round_trip(kRoundTrips)) {
    const double floor = to_seconds(in_process) + static_cast<double>(waits) * to_seconds(*trip);
    std::printf(
        "  the floor on this machine: one bare hand-over between two processes (a futex, there and back, %s): "
        "%.1f us\n",
        pin.pinned() ? "on this core" : "not pinned", to_seconds(*trip) * 1e6);
    std::printf(
        "    the processes' %llu waits at that cost alone: %.3f s; with the in-process run's %.3f s, at best %.2f of "
        "the in-process speed\n",
        static_cast<unsigned long long>(waits), static_cast<double>(waits) * to_seconds(*trip), to_seconds(in_process),
        to_seconds(in_process) / floor);
    // The processes' own running is theirs to spend (their code, their reads
    // and writes of the bus, the shim's bookkeeping), whatever canhil does.
    std::printf(
        "    and with the processes' own running as measured above (%.3f s), at best %.2f of the in-process speed\n",
        running, to_seconds(in_process) / (floor + running));
  } else {
    std::printf("  the floor on this machine: NOT MEASURED (no second process could be started)\n");
  }
  return factor >= kTarget;
}

}  // namespace canhil::app
