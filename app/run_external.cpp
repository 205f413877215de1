// app/run_external.cpp — `canhil run --external` (run_external.hpp).
#include "run_external.hpp"

#include "run_realtime.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/external_driver.hpp"
#include "canhil/emulator/referee.hpp"
#include "canhil/external/external_run.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "log_file.hpp"
#include "play_summary.hpp"
#include "run_realtime.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

void print_summary(const emulator::Session& session, const emulator::ExternalDriver& driver,
                   const lockstep::Conductor& conductor, Nanos wall, const char* how) {
  const double simulated = to_seconds(driver.now());
  const double w = to_seconds(wall);
  std::printf("canhil run: %s after %.2f s of virtual time in %.2f s of wall time (%.1fx real time)\n", how, simulated,
              w, w > 0 ? simulated / w : 0.0);
  const emulator::WorldSnapshot s = session.snapshot();
  std::printf("  ball at (%.2f, %.2f)\n", s.ball.x(), s.ball.y());
  print_play(session, stdout);
  const auto& teams = session.scenario().teams;
  for (std::size_t r = 0; r < session.robot_count(); ++r) {
    const emulator::Rig& rig = session.rig(r);
    const std::string team = teams.size() > 1 ? " (" + teams[rig.team].name + ")" : "";
    std::printf("  %s agent %d%s: at (%.2f, %.2f)\n", rig.interface.c_str(), rig.agent, team.c_str(), s.robots[r].x_m,
                s.robots[r].y_m);
  }
  std::printf("  frames: %llu from the processes, %llu physics steps\n",
              static_cast<unsigned long long>(driver.frames_from_processes()),
              static_cast<unsigned long long>(driver.physics_steps()));
  const Nanos waited = conductor.waited_wall();
  std::printf("  wall time: canhil %.3f s (%.0f %%), waiting for the processes %.3f s (%.0f %%)\n",
              to_seconds(wall - waited), w > 0 ? 100 * to_seconds(wall - waited) / w : 0.0, to_seconds(waited),
              w > 0 ? 100 * to_seconds(waited) / w : 0.0);
  std::printf("    canhil's looks before sleeping ([external] spin_us): %llu answered, %llu ended in a sleep\n",
              static_cast<unsigned long long>(conductor.looks_answered()),
              static_cast<unsigned long long>(conductor.sleeps()));
  for (const lockstep::ProcessReport& p : conductor.processes()) {
    std::printf("    %-16s pid %-7d %.3f s running, %llu waits, %llu CAN frames written, %d thread(s)\n",
                p.name.c_str(), p.pid, to_seconds(p.busy_wall), static_cast<unsigned long long>(p.blocks),
                static_cast<unsigned long long>(p.frames_sent), p.threads);
  }
  for (const auto& c : session.fault_counts()) {
    std::printf("  fault %-24s %s\n", c.rule.c_str(), can_nodes::describe(c).c_str());
  }
  std::fputs(session.world().solver_health().describe("  ").c_str(), stdout);
}

}  // namespace

int run_external(emulator::Session& session, const ExternalRequest& run, const std::string& shim,
                 const std::string& team_preload, ExternalFigures* figures) {
  external::ExternalSetup setup;
  setup.shim = shim;
  setup.team_preload = team_preload;
  setup.wait_for = run.wait_for;
  external::ExternalRun started(session, std::move(setup));
  const std::size_t robots = session.robot_count();
  std::printf("canhil run: %zu robot(s), virtual time with external processes, %g s (%s), seed %llu\n", robots,
              run.length.seconds, run.length.source.c_str(), static_cast<unsigned long long>(session.scenario().seed));
  say_the_wire(stdout, session, started.driver().timed_wire(), "this run's clock");
  for (std::size_t r = 0; r < robots; ++r) {
    const emulator::Rig& rig = session.rig(r);
    std::printf("  robot %zu on %s (%s) for agent %d\n", r, rig.interface.c_str(), can_nodes::bus_of(rig.interface),
                rig.agent);
  }
  stop_on_signals();
  int status = 0;
  const char* how = "done";
  Nanos wall_start = lockstep::wall_clock();
  bool attached = false;
  try {
    started.start();
    attached = true;
    wall_start = lockstep::wall_clock();
    const Nanos total = from_seconds(run.length.seconds);
    std::size_t calls_shown = 0;
    while (started.now() < total && !g_stop) {
      started.run_until(std::min<Nanos>(started.now() + std::chrono::seconds(1), total));
      if (run.quiet) continue;
      const emulator::WorldSnapshot s = session.snapshot();
      std::printf("  t=%5.1f s  ball (%6.2f, %5.2f)", to_seconds(started.now()), s.ball.x(), s.ball.y());
      for (std::size_t r = 0; r < robots; ++r) {
        std::printf("  %s (%5.2f, %5.2f)", session.rig(r).interface.c_str(), s.robots[r].x_m, s.robots[r].y_m);
      }
      std::printf("\n");
      if (const emulator::Referee* referee = session.referee()) {  // the calls of that second, as they came
        for (; calls_shown < referee->calls().size(); ++calls_shown) {
          const emulator::RefereeCall& c = referee->calls()[calls_shown];
          std::printf("  t=%5.1f s  referee: %s\n", to_seconds(c.time), c.text.c_str());
        }
      }
      std::fflush(stdout);
    }
  } catch (const emulator::ProcessStuck& e) {
    status = external::kProcessStuckStatus;
    if (attached) {
      std::fprintf(stderr, "canhil run: stopped %s\n", e.what());
      how = "stopped (a process did not answer, or never ran)";
    } else {
      std::fprintf(stderr, "canhil run: %s\n", e.what());
      how = "not started";
    }
  }
  if (g_stop && status == 0) {
    status = 130;
    how = "stopped";
  }
  const Nanos wall = lockstep::wall_clock() - wall_start;
  started.stop();
  print_summary(session, started.driver(), started.conductor(), wall, how);
  if (figures != nullptr) {
    const lockstep::Conductor& c = started.conductor();
    *figures = ExternalFigures{started.now(), wall, c.waited_wall(), c.processes(), c.looks_answered(), c.sleeps()};
  }
  if (run.trace) {
    write_file(*run.trace, started.driver().trace(), "trace");
    std::printf("trace written to %s (candump log in virtual time)\n", run.trace->c_str());
  }
  if (run.world_log) {
    write_file(*run.world_log, session.world_log(), "world log");
    std::printf("world log written to %s\n", run.world_log->c_str());
  }
  return status;
}

}  // namespace canhil::app
