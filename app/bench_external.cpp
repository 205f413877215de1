// app/bench_external.cpp — `canhil bench --part external` (bench_external.hpp).
#include "bench_external.hpp"

#include <sched.h>

#include <chrono>
#include <cstdio>

#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "run_external.hpp"

namespace canhil::app {
namespace {

constexpr double kTarget = 20;  // times real time, one robot, one core

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

// The same scenario in-process, virtual time, everything on: its wall time.
Nanos in_process_wall(const emulator::Scenario& sc, double seconds,
                      const std::shared_ptr<const frames::MessageSet>& messages) {
  emulator::SessionOptions options;
  options.messages = messages;
  emulator::Session session(sc, options);
  emulator::VirtualOptions virtual_options;
  virtual_options.record_trace = false;
  emulator::VirtualDriver run(session, virtual_options);
  const Nanos start = lockstep::wall_clock();
  run.run_for(from_seconds(seconds));
  return lockstep::wall_clock() - start;
}

}  // namespace

bool bench_external(const ExternalBench& bench, const std::shared_ptr<const frames::MessageSet>& messages) {
  emulator::Scenario sc = emulator::load_scenario(emulator::shipped_scenario("one_robot.toml"));
  sc.interfaces = {bench.iface};
  const physics::Placement& at = sc.world.robots.at(0);
  char agent[96];
  std::snprintf(agent, sizeof agent, "canhil-agent --pose %g,%g,%g", at.x_m, at.y_m, at.heading_deg);
  sc.external.processes = {"canhil-hwcomm --iface {iface}", agent};
  const PinnedToCore pin(bench.cpu);
  std::printf(
      "canhil bench: external processes: one robot on %s, %g s of virtual time each, %s: in-process, then "
      "`%s` and `%s` as processes in lockstep\n",
      bench.iface.c_str(), bench.seconds,
      pin.pinned() ? ("all on CPU " + std::to_string(bench.cpu)).c_str() : "not pinned to a core",
      sc.external.processes[0].c_str(), sc.external.processes[1].c_str());
  std::fflush(stdout);
  const Nanos in_process = in_process_wall(sc, bench.seconds, messages);

  emulator::SessionOptions options;
  options.messages = messages;
  options.external = true;
  emulator::Session session(sc, options);
  ExternalRun run;
  run.length = {bench.seconds, "the bench"};
  run.quiet = true;
  ExternalFigures fig;
  const int status = run_external(session, run, bench.shim, bench.team_preload, &fig);
  if (status != 0 || fig.simulated < from_seconds(bench.seconds)) {
    std::printf("  external run: NOT MEASURED (canhil run --external ended with status %d at t = %.3f s)\n", status,
                to_seconds(fig.simulated));
    return false;
  }
  const double factor_in = bench.seconds / to_seconds(in_process);
  const double wall = to_seconds(fig.wall);
  const double factor = bench.seconds / wall;
  std::printf("  in-process, canhil's handler and agent:         %7.1fx real time (wall %.3f s)\n", factor_in,
              to_seconds(in_process));
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
  return factor >= kTarget;
}

}  // namespace canhil::app
