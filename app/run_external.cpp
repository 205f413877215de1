// app/run_external.cpp — `canhil run --external` (run_external.hpp).
#include "run_external.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "args.hpp"
#include "canhil/base/assets.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/external_driver.hpp"
#include "canhil/emulator/referee.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "play_summary.hpp"
#include "private_rtdb.hpp"
#include "stop_signals.hpp"
#include "team_processes.hpp"

namespace canhil::app {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRestartedVariable = "CANHIL_TIMESHIM_RESTARTED";
constexpr const char* kTeamPreloadVariable = "CANHIL_TEAM_PRELOAD";

void write_text(const std::string& path, const std::string& text, const char* what) {
  std::ofstream out(path);
  out << text;
  if (!out) throw UsageError("cannot write the " + std::string(what) + " to " + path);
}

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

std::string find_timeshim() {
  if (const auto given = path_from_environment("CANHIL_TIMESHIM")) {
    if (!fs::exists(*given)) throw SetupError("CANHIL_TIMESHIM=" + given->string() + ": no such file");
    return fs::absolute(*given).string();
  }
  const fs::path here = program_folder();
  std::vector<fs::path> places = {here.parent_path() / CANHIL_INSTALL_LIBDIR / "libcanhil-timeshim.so",
                                  CANHIL_BUILD_TIMESHIM};
  std::string looked;
  for (const fs::path& p : places) {
    std::error_code ec;
    if (fs::exists(p, ec)) return p.string();
    looked += (looked.empty() ? "" : ", ") + p.string();
  }
  throw SetupError("the time shim libcanhil-timeshim.so is not at " + looked +
                   ": build it (target canhil_timeshim) or set CANHIL_TIMESHIM=/path/to/libcanhil-timeshim.so");
}

std::string preload_shim_into_self(const std::string& shim) {
  if (dlsym(RTLD_DEFAULT, "canhil_timeshim_conduct") != nullptr) {
    // Started again with the shim: the team's processes get the preload canhil was first given.
    const char* team = std::getenv(kTeamPreloadVariable);
    std::string preload = team != nullptr ? team : "";
    if (preload.empty()) {
      unsetenv("LD_PRELOAD");
    } else {
      setenv("LD_PRELOAD", preload.c_str(), 1);
    }
    unsetenv(kTeamPreloadVariable);
    unsetenv(kRestartedVariable);
    return preload;
  }
  if (std::getenv(kRestartedVariable) != nullptr) {
    throw SetupError("canhil started itself again with LD_PRELOAD=" + shim +
                     " and the shim is still not loaded: is it a library for this machine? (`ldd " + shim + "`)");
  }
  const char* team = std::getenv("LD_PRELOAD");
  const std::string team_preload = team != nullptr ? team : "";
  setenv(kTeamPreloadVariable, team_preload.c_str(), 1);
  setenv(kRestartedVariable, "1", 1);
  setenv("LD_PRELOAD", (team_preload.empty() ? shim : shim + ":" + team_preload).c_str(), 1);
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> words;
  for (std::size_t at = 0; at < all.size();) {
    const std::size_t end = all.find('\0', at);
    words.push_back(all.substr(at, end - at));
    at = end == std::string::npos ? all.size() : end + 1;
  }
  std::vector<char*> argv;
  argv.reserve(words.size() + 1);
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  // The keys this image claimed: the one started next claims its own (a claim
  // kept across the exec had no owner to give it back, until the next run).
  release_private_rtdb_keys();
  execv("/proc/self/exe", argv.data());
  throw SetupError(std::string("canhil could not start itself again with the time shim: ") + std::strerror(errno));
}

int run_external(emulator::Session& session, const ExternalRun& run, const std::string& shim,
                 const std::string& team_preload, ExternalFigures* figures) {
  const double attach_limit = attach_limit_s(session.scenario());
  lockstep::Conductor conductor(conductor_options(session.scenario()));
  emulator::ExternalOptions driver_options;
  driver_options.start_limit = from_seconds(attach_limit);
  emulator::ExternalDriver driver(session, conductor, driver_options);
  const auto spin = spin_the_bus(session);
  const std::size_t robots = session.robot_count();
  std::printf("canhil run: %zu robot(s), virtual time with external processes, %g s (%s), seed %llu\n", robots,
              run.length.seconds, run.length.source.c_str(), static_cast<unsigned long long>(session.scenario().seed));
  for (std::size_t r = 0; r < robots; ++r) {
    const emulator::Rig& rig = session.rig(r);
    std::printf("  robot %zu on %s (%s) for agent %d\n", r, rig.interface.c_str(), can_nodes::bus_of(rig.interface),
                rig.agent);
  }
  std::size_t expected = 0;
  const std::vector<std::string> environment =
      conductor.environment(shim, team_preload.empty() ? nullptr : team_preload.c_str());
  const emulator::Scenario& scenario = session.scenario();
  bool any_processes = false;
  for (std::size_t t = 0; t < scenario.teams.size(); ++t) any_processes |= !scenario.external_of(t).processes.empty();
  TeamProcesses started(environment, stdout);
  if (any_processes) {
    expected = started.start_all(session);
  } else {
    expected = run.wait_for > 0 ? run.wait_for : 2 * robots;
    std::printf("  start your handler and agent (AGENT=N) with:\n   ");
    for (const std::string& e : environment) std::printf(" %s", e.c_str());
    if (scenario.external.syslog == "system") std::printf(" CANHIL_SYSLOG=system");
    std::printf("\n  waiting for %zu process(es), %g s at most\n", expected, attach_limit);
  }
  std::fflush(stdout);
  stop_on_signals();
  const std::size_t attached = conductor.wait_attached(expected, from_seconds(attach_limit));
  int status = 0;
  const char* how = "done";
  const Nanos wall_start = lockstep::wall_clock();
  if (attached < expected) {
    std::fprintf(
        stderr,
        "canhil run: %zu of %zu process(es) attached within %g s (attach_limit_s in [external] or [teams.external])\n",
        attached, expected, attach_limit);
    status = kProcessStuckStatus;
    how = "not started";
  } else {
    const Nanos total = from_seconds(run.length.seconds);
    std::size_t calls_shown = 0;
    try {
      while (driver.now() < total && !g_stop) {
        driver.run_until(std::min<Nanos>(driver.now() + std::chrono::seconds(1), total));
        started.reap(driver.now());
        if (const std::string why = started.not_started(); !why.empty()) throw emulator::ProcessStuck(why);
        if (run.quiet) continue;
        const emulator::WorldSnapshot s = session.snapshot();
        std::printf("  t=%5.1f s  ball (%6.2f, %5.2f)", to_seconds(driver.now()), s.ball.x(), s.ball.y());
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
      std::fprintf(stderr, "canhil run: stopped at t = %.3f s: %s\n", to_seconds(driver.now()), e.what());
      status = kProcessStuckStatus;
      how = "stopped (a process did not answer, or never ran)";
    }
    if (g_stop && status == 0) {
      status = 130;
      how = "stopped";
    }
  }
  const Nanos wall = lockstep::wall_clock() - wall_start;
  conductor.release();  // the run is over: their waits end, they take their SIGINT
  started.stop_all();
  print_summary(session, driver, conductor, wall, how);
  if (figures != nullptr)
    *figures = ExternalFigures{
        driver.now(),      wall, conductor.waited_wall(), conductor.processes(), conductor.looks_answered(),
        conductor.sleeps()};
  if (run.trace) {
    write_text(*run.trace, driver.trace(), "trace");
    std::printf("trace written to %s (candump log in virtual time)\n", run.trace->c_str());
  }
  if (run.world_log) {
    write_text(*run.world_log, session.world_log(), "world log");
    std::printf("world log written to %s\n", run.world_log->c_str());
  }
  return status;
}

}  // namespace canhil::app
