// `canhil bench`: the figures a team checks on its own machine, in one run,
// each against its target:
//   virtual  the real-time factor of the five-robot scenario in virtual time,
//            everything on (nodes, buses, physics, vision, handlers, agents);
//            target at least 100x
//   jitter   release jitter (p99) of the emulator's trigger messages in real
//            time, the one-robot scenario with everything on, against a bare
//            clock_nanosleep loop on the same period; target at most 1.2x
//   vcan     the highest frame rate through the interface with no loss, canhil's
//            sockets against can-utils' `cangen -g 0`; target at least 0.8x
//   external the one-robot real-time factor with the reference handler and
//            agent as processes in lockstep, next to in-process, one core;
//            target at least 20x (bench_external.cpp)
//   view     the five-robot virtual-time factor with a page connected to the
//            viewer against without; target at least 0.9 of it (bench_view.cpp)
//   match    five robots and a ten-robot match half on one core, physics alone
//            for scale; targets 180x and 80x (bench_match.hpp)
//   jobs     match halves per minute with canhil match --jobs 2 against --jobs 1;
//            target at least 1.8x (bench_jobs.hpp)
//   analyse  timing --analyse of a 200-message set, FTT-CAN and native; target
//            at most 50 ms (bench_analyse.hpp)
//   wire     the five-robot virtual-time run on timed wires against instant
//            buses; target at least 0.9 of its speed (bench_wire.hpp)
// The last three need SocketCAN (vcan_setup/with-vcan.sh where the kernel has none).
#include <sched.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <sstream>
#include <thread>

#include "bench_analyse.hpp"
#include "bench_external.hpp"
#include "bench_jobs.hpp"
#include "bench_match.hpp"
#include "bench_realtime.hpp"
#include "bench_view.hpp"
#include "bench_wire.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/external/private_rtdb.hpp"
#include "canhil/external/time_shim.hpp"
#include "canhil/frames/ftt.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "run_external.hpp"

namespace canhil::app {
namespace {

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// The five-robot scenario (or `config`) in virtual time, everything on: true when at least 100x.
bool bench_virtual(const std::optional<std::string>& config, double seconds,
                   const std::shared_ptr<const frames::MessageSet>& messages) {
  const std::filesystem::path path =
      config ? std::filesystem::path(*config) : emulator::shipped_scenario("five_robots.toml");
  const emulator::Scenario sc = emulator::load_scenario(path);
  std::printf("canhil bench: virtual time: %s, %zu robot(s), %zu obstacle(s), %g s of virtual time\n",
              path.string().c_str(), sc.world.robots.size(), sc.world.obstacles.size(), seconds);
  emulator::SessionOptions options;
  options.messages = messages;
  const double cpu0 = cpu_seconds();
  const auto wall0 = std::chrono::steady_clock::now();
  emulator::Session session(emulator::plan_run(sc, options));
  emulator::VirtualOptions virtual_options;
  virtual_options.record_trace = false;  // as canhil run without --trace: frames counted
  emulator::VirtualDriver run(session, virtual_options);
  run.run_for(from_seconds(seconds));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double cpu = cpu_seconds() - cpu0;
  std::uint64_t frames = 0;
  for (const auto& o : run.outcomes()) frames += o.frames;
  const double factor = seconds / wall;
  std::printf(
      "  real-time factor, everything on: %.0fx (wall %.3f s, CPU %.3f s = %.0fx of one core)  target >= 100x: %s\n",
      factor, wall, cpu, seconds / cpu, factor >= 100 ? "met" : "MISSED");
  std::printf("  frames on the buses: %llu (%.0f per simulated second)\n", static_cast<unsigned long long>(frames),
              static_cast<double>(frames) / seconds);
  return factor >= 100;
}

// TM release jitter of canhil run against a bare loop on the same period: true when p99 <= 1.2x.
bool bench_jitter(const std::string& iface, double seconds, int priority,
                  const std::shared_ptr<const frames::MessageSet>& messages) {
  const Nanos ec = frames::FttConfig{}.elementary_cycle;  // canhil run's
  std::printf(
      "canhil bench: real time on %s (%s), %g s each, SCHED_FIFO %d: a bare clock_nanosleep loop, canhil run, then "
      "both\n",
      iface.c_str(), can_nodes::bus_of(iface), seconds, priority);
  emulator::SessionOptions session;
  session.messages = messages;
  emulator::RealtimeOptions opt;
  opt.priority = priority;
  const JitterFigures bare = bare_loop_jitter(iface, seconds, ec, priority);
  const emulator::Scenario one = emulator::read_scenario(emulator::shipped_scenario("one_robot.toml"));
  const JitterFigures emu = emulator_jitter(iface, seconds, one, session, opt);
  // The same bare loop while canhil run runs: what the machine itself does
  // under that load (a diagnostic, not the target's reference).
  JitterFigures loaded;
  std::thread beside([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    loaded = bare_loop_jitter(iface, seconds - 1, ec, priority);
  });
  emulator_jitter(iface, seconds, one, session, opt);
  beside.join();
  const auto line = [](const char* what, const JitterFigures& j) {
    std::printf("  %-34s %6zu releases, %4llu missing  p50 %8.1f us  p99 %8.1f us  max %8.1f us\n", what, j.releases,
                static_cast<unsigned long long>(j.missing), j.p50_us, j.p99_us, j.max_us);
  };
  line("bare loop, a frame every 10 ms:", bare);
  line("canhil run, trigger messages:", emu);
  line("bare loop beside canhil run:", loaded);
  const bool measured = bare.releases > 0 && emu.releases > 0;
  const double ratio = bare.p99_us > 0 ? emu.p99_us / bare.p99_us : 0;
  const bool met = measured && ratio <= 1.2;
  std::printf("  release jitter p99, canhil / bare loop: %.2fx  target <= 1.2x: %s\n", ratio, met ? "met" : "MISSED");
  if (!met && loaded.p99_us > 1.2 * bare.p99_us) {
    std::printf("  (the machine itself: the bare loop's p99 is %.1fx its idle figure while canhil run runs)\n",
                loaded.p99_us / bare.p99_us);
  }
  return met;
}

// The highest lossless frame rate through the interface against cangen -g 0: true when at least 0.8x.
bool bench_vcan(const std::string& iface, std::uint64_t frames) {
  std::printf("canhil bench: frame rate through %s (%s), %llu frames at full speed, one listening socket\n",
              iface.c_str(), can_nodes::bus_of(iface), static_cast<unsigned long long>(frames));
  const RateFigures ours = canhil_rate(iface, frames);
  const RateFigures reference = cangen_rate(iface, frames);
  const auto line = [](const char* what, const RateFigures& r) {
    std::printf("  %-34s %9.0f frames/s  (%llu sent, %llu received, %llu lost)\n", what, r.frames_per_s,
                static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.received),
                static_cast<unsigned long long>(r.lost));
  };
  line("canhil, highest rate with no loss:", ours);
  line("cangen -g 0:", reference);
  const double ratio = reference.frames_per_s > 0 ? ours.frames_per_s / reference.frames_per_s : 0;
  const bool met = ours.lost == 0 && ratio >= 0.8;
  std::printf("  lossless rate, canhil / cangen: %.2fx  target >= 0.8x: %s\n", ratio, met ? "met" : "MISSED");
  return met;
}

}  // namespace

int run_bench(Args& args, const std::optional<std::string>& dbc) {
  const double seconds = number_option(args, "--seconds", 60);
  const double rt_seconds = number_option(args, "--rt-seconds", 10);
  const double rate_frames = number_option(args, "--frames", 200'000);
  const std::string iface = args.option("--iface").value_or("vcan0");
  const std::string parts = args.option("--part").value_or("virtual,view,match,jobs,analyse,wire,jitter,vcan,external");
  const double priority_option = number_option(args, "--priority", 40);
  const auto config = args.option("--config");
  const double cpu_option = number_option(args, "--cpu", 0);
  if (args.positionals().size() != 1) throw UsageError("bench takes no other arguments");
  if (!(seconds > 0)) throw UsageError("--seconds takes a number above 0");
  if (!(rt_seconds >= 2)) throw UsageError("--rt-seconds takes 2 or more");
  if (!(rate_frames >= 1000 && rate_frames <= 1e8)) throw UsageError("--frames takes 1000..100000000");
  if (!(priority_option >= 0 && priority_option <= 99)) throw UsageError("--priority takes 0..99");
  if (!(cpu_option >= -1 && cpu_option < CPU_SETSIZE)) throw UsageError("--cpu takes a core number, or -1 for none");
  const int priority = static_cast<int>(priority_option);
  bool want_virtual = false, want_view = false, want_jitter = false, want_vcan = false, want_external = false,
       want_match = false, want_analyse = false, want_jobs = false, want_wire = false;
  {
    std::istringstream in(parts);
    for (std::string part; std::getline(in, part, ',');) {
      if (part == "virtual") {
        want_virtual = true;
      } else if (part == "jitter") {
        want_jitter = true;
      } else if (part == "vcan") {
        want_vcan = true;
      } else if (part == "view") {
        want_view = true;
      } else if (part == "match") {
        want_match = true;
      } else if (part == "external") {
        want_external = true;
      } else if (part == "jobs") {
        want_jobs = true;
      } else if (part == "analyse" || part == "analyze") {
        want_analyse = true;
      } else if (part == "wire") {
        want_wire = true;
      } else {
        throw UsageError(
            "--part takes virtual, view, match, jobs, analyse, wire, jitter, vcan and external, comma-separated; got "
            "'" +
            part + "'");
      }
    }
  }
  ExternalBench external;
  if (want_external && can_nodes::kernel_has_can()) {
    // Before anything is measured: canhil may start itself again, with the time shim preloaded.
    external.shim = external::find_timeshim();
    external.team_preload = external::preload_shim_into_self(external.shim);
  }
  external::use_private_rtdb_keys(external::kBenchKeyPrefix);
  const auto messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  bool all_met = true;
  if (want_virtual) all_met = bench_virtual(config, seconds, messages) && all_met;
  if (want_view) all_met = bench_view(config, seconds, messages) && all_met;
  if (want_match) all_met = bench_match(config, seconds, messages) && all_met;
  if (want_jobs) all_met = bench_jobs(config, seconds, messages) && all_met;
  if (want_analyse) all_met = bench_analyse() && all_met;
  if (want_wire) all_met = bench_wire(config, seconds, messages) && all_met;
  if (!want_jitter && !want_vcan && !want_external) return all_met ? 0 : 1;
  if (!can_nodes::kernel_has_can()) {
    std::printf(
        "canhil bench: release jitter, vcan rate and external processes NOT MEASURED: this kernel has no SocketCAN; "
        "run `vcan_setup/with-vcan.sh -- canhil bench` (or --part virtual)\n");
    return 1;
  }
  if (want_jitter) all_met = bench_jitter(iface, rt_seconds, priority, messages) && all_met;
  if (want_vcan) all_met = bench_vcan(iface, static_cast<std::uint64_t>(rate_frames)) && all_met;
  if (want_external) {
    external.iface = iface;
    external.seconds = seconds;
    external.cpu = static_cast<int>(cpu_option);
    all_met = bench_external(external, messages) && all_met;
  }
  return all_met ? 0 : 1;
}

}  // namespace canhil::app
