// `canhil run [--virtual-time] [--config SCENARIO] ...`: a scenario
// (emulator/scenario.hpp; the shipped one-robot scenario by default) as a
// session, driven in virtual time (the whole loop in one process, with a
// trace and a world log) or in real time on SocketCAN next to the team's
// handler and agent. Faults work in both. This file reads the options and
// prints; the run itself is emulator::Session and its drivers.
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "canhil/control/run_commands.hpp"
#include "canhil/control/save_commands.hpp"
#include "canhil/control/unix_server.hpp"
#include "canhil/emulator/run_control.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/viewer/live_feed.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "play_summary.hpp"
#include "run_external.hpp"
#include "run_realtime.hpp"
#include "run_view.hpp"
#include "team_processes.hpp"
#include "virtual_loop.hpp"

namespace canhil::app {
namespace {

std::atomic<bool> g_stop_run{false};
extern "C" void stop_run(int) { g_stop_run = true; }

void write_file(const std::string& path, const std::string& text, const char* what) {
  std::ofstream out(path);
  out << text;
  if (!out) throw UsageError("cannot write the " + std::string(what) + " to " + path);
}

// A saved world (--restore-world), or a usage error naming the file and what is wrong.
physics::WorldState load_world(const std::string& path) {
  try {
    return physics::load_state(path);
  } catch (const SetupError& e) {
    throw UsageError("--restore-world " + path + ": " + e.what());
  }
}

// The summary of a virtual-time run.
void print_virtual_summary(const emulator::Session& session, const emulator::VirtualDriver& driver, double wall_s) {
  const double simulated = to_seconds(driver.now());
  std::printf("canhil run: %s after %.2f s of virtual time in %.2f s of wall time (%.0fx real time)\n",
              g_stop_run ? "stopped" : "done", simulated, wall_s, wall_s > 0 ? simulated / wall_s : 0.0);
  const Eigen::Vector3d b = session.world().ball_position();
  std::printf("  ball at (%.2f, %.2f)\n", b.x(), b.y());
  const auto& teams = session.scenario().teams;
  print_play(session, stdout);
  const auto outcomes = driver.outcomes();
  for (std::size_t r = 0; r < outcomes.size(); ++r) {
    const auto& o = outcomes[r];
    const emulator::Rig& rig = session.rig(r);
    const std::string team = teams.size() > 1 ? " (" + teams[rig.team].name + ")" : "";
    std::printf("  %s agent %d%s: at (%.2f, %.2f), %d kick(s), %llu frames, %llu bad, 24 V pack %.1f V (%.0f %%)\n",
                rig.interface.c_str(), rig.agent, team.c_str(), o.pose.x_m, o.pose.y_m, o.kicks,
                static_cast<unsigned long long>(o.frames), static_cast<unsigned long long>(o.bad_frames),
                o.battery.power24_v, 100 * o.charge[2]);
  }
  for (const auto& c : session.fault_counts()) {
    std::printf("  fault %-24s %s\n", c.rule.c_str(), can_nodes::describe(c).c_str());
  }
  std::fputs(session.world().solver_health().describe("  ").c_str(), stdout);
}

struct VirtualOutputs {
  std::optional<std::string> trace, world_log, save_world;
  double log_period_s = 0.05;
  bool quiet = false;
};

// The run's clock as the viewer and the control socket set it (pause, step,
// speed): virtual time goes as far as RunControl's plan says, and while it
// stands the session still takes changes (a robot dragged while paused moves).
int run_virtual(emulator::Session& session, const emulator::RunLength& length, const VirtualOutputs& out,
                emulator::RunControl& control, viewer::LiveFeed& feed) {
  emulator::VirtualOptions options;
  options.record_trace = out.trace.has_value();  // a long run without --trace keeps no frames
  emulator::VirtualDriver driver(session, options);
  const emulator::Scenario& sc = session.scenario();
  std::printf("canhil run: %zu robot(s), virtual time, %g s (%s), seed %llu, %zu fault rule(s)\n", sc.robot_count(),
              length.seconds, length.source.c_str(), static_cast<unsigned long long>(sc.seed), sc.faults.size());
  std::fflush(stdout);
  std::signal(SIGINT, stop_run);
  std::signal(SIGTERM, stop_run);
  const Nanos total = from_seconds(length.seconds);
  const auto wall_start = std::chrono::steady_clock::now();
  drive_virtual(driver, session, control, total, g_stop_run, [&] {
    if (out.quiet) return;
    const emulator::WorldSnapshot s = session.snapshot();
    const auto o = driver.outcomes();
    std::printf("  t=%5.1f s  ball (%6.2f, %5.2f)", to_seconds(driver.now()), s.ball.x(), s.ball.y());
    for (std::size_t r = 0; r < o.size(); ++r) {
      std::printf("  %s (%5.2f, %5.2f) kicks %d", session.rig(r).interface.c_str(), o[r].pose.x_m, o[r].pose.y_m,
                  o[r].kicks);
    }
    std::printf("\n");
    std::fflush(stdout);
  });
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  feed.set_ended();
  // The files are written after the summary: a path that cannot be written must not cost the run's outcome.
  print_virtual_summary(session, driver, wall);
  if (out.trace) {
    write_file(*out.trace, driver.trace(), "trace");
    std::printf("trace written to %s (candump log; check it with `canhil timing %s`)\n", out.trace->c_str(),
                out.trace->c_str());
  }
  if (out.save_world) {
    physics::save_state(session.world().save(), *out.save_world);
    std::printf("world saved to %s (start a run from it with --restore-world)\n", out.save_world->c_str());
  }
  if (out.world_log) {
    write_file(*out.world_log, session.world_log(), "world log");
    std::printf("world log written to %s (CSV, one line every %g s)\n", out.world_log->c_str(), out.log_period_s);
  }
  return g_stop_run ? 130 : 0;
}

// The run's control socket (canhil coach, scripts): --control PATH (an error
// when it cannot be served), or the default one; when another run holds the
// default, this run's own beside it. Where neither can be served (a /tmp on a
// filesystem without sockets, such as 9p or some NFS), the run goes on without
// one and says so.
std::unique_ptr<control::UnixServer> serve_control(control::Commands& commands, const std::optional<std::string>& path,
                                                   FILE* out) {
  std::unique_ptr<control::UnixServer> server;
  if (path) {
    server = std::make_unique<control::UnixServer>(*path, commands);
  } else {
    try {
      server = std::make_unique<control::UnixServer>(control::default_socket_path(), commands);
    } catch (const SetupError&) {
      try {
        server = std::make_unique<control::UnixServer>(
            control::default_socket_path().string() + "-" + std::to_string(getpid()), commands);
      } catch (const SetupError& e) {
        std::fprintf(stderr,
                     "canhil run: warning: no control socket (%s); canhil coach cannot reach this run. Set "
                     "XDG_RUNTIME_DIR or give --control PATH on a local filesystem, or --no-control to say so.\n",
                     e.what());
        return nullptr;
      }
    }
  }
  std::fprintf(out, "canhil run: control socket %s (canhil coach --control %s start|stop|status)\n",
               server->path().c_str(), server->path().c_str());
  return server;
}

// What the viewer and the control socket do shows in the run's log, and on every page.
void log_commands(control::Commands& commands, viewer::Server* shown) {
  commands.on_done([shown](const std::string& line) {
    std::printf("canhil run: %s\n", line.c_str());
    std::fflush(stdout);
    if (shown != nullptr) shown->log(line);
  });
}

// The team's laptop side from the command line, over the scenario's [laptop].
void laptop_options(Args& args, emulator::LaptopSide& side) {
  if (auto v = args.option("--rtdb-lib")) side.rtdb_lib = *v;
  if (auto v = args.option("--rtdb-items")) side.rtdb_items = *v;
  if (auto v = args.option("--rtdb-ini")) side.rtdb_ini = *v;
  if (auto v = args.option("--layout")) side.layout = *v;
  const auto pman_lib = args.option("--pman-lib");
  const bool no_pman = args.flag("--no-pman");
  if (pman_lib && no_pman) throw UsageError("give --pman-lib PATH or --no-pman, not both");
  if (pman_lib) side.pman = *pman_lib;
  if (no_pman) side.pman = "none";
}

}  // namespace

int run_run(Args& args, const std::optional<std::string>& dbc) {
  const bool external = args.flag("--external");
  const bool virtual_time = args.flag("--virtual-time") || external;  // --external runs in virtual time
  std::vector<std::string> processes;
  while (auto p = args.option("--process")) processes.push_back(*p);
  const std::optional<double> answer_limit = optional_number(args, "--answer-limit");
  const std::optional<double> wait_for = optional_number(args, "--wait-for");
  const auto config = args.option("--config");
  VirtualOutputs outputs;
  outputs.trace = args.option("--trace");
  outputs.world_log = args.option("--world-log");
  outputs.save_world = args.option("--save-world");
  const auto restore_world = args.option("--restore-world");
  std::vector<std::string> fault_texts;
  while (auto f = args.option("--fault")) fault_texts.push_back(*f);
  const std::optional<std::uint64_t> seed = seed_option(args);
  outputs.quiet = args.flag("--quiet");
  const auto control_path = args.option("--control");
  const ViewChoice view = view_options(args);
  const auto speed_text = args.option("--speed");
  const bool start_paused = args.flag("--paused");
  const bool no_control = args.flag("--no-control");
  if (control_path && no_control) throw UsageError("give --control PATH or --no-control, not both");
  emulator::Scenario scenario =
      emulator::load_scenario(config ? std::filesystem::path(*config) : emulator::shipped_scenario("one_robot.toml"));
  laptop_options(args, scenario.laptop);
  const std::optional<double> duration_given = optional_number(args, "--duration");
  const double bit_rate = number_option(args, "--bit-rate", 1'000'000);
  const double rx_buffer_kb = number_option(args, "--rx-buffer-kb", 1024);
  const double priority = number_option(args, "--priority", 40);
  outputs.log_period_s = number_option(args, "--world-log-period", 0.05);
  scenario.kick_power = static_cast<int>(number_option(args, "--kick-power", scenario.kick_power));
  if (seed) scenario.seed = *seed;
  if (args.positionals().size() != 1) throw UsageError("run takes no other arguments");
  if (!external && (!processes.empty() || answer_limit || wait_for)) {
    throw UsageError("--process, --answer-limit and --wait-for are for runs with --external");
  }
  apply_external_options(scenario, processes, answer_limit);
  if (wait_for && !(*wait_for >= 1 && *wait_for <= 64 && *wait_for == static_cast<int>(*wait_for))) {
    throw UsageError("--wait-for takes a number of processes, 1..64");
  }
  const emulator::RunLength length = [&] {
    try {
      return scenario.run_length(duration_given, !virtual_time);
    } catch (const SetupError& e) {
      throw UsageError(e.what());
    }
  }();
  double speed = 0;  // as fast as possible
  if (speed_text && *speed_text != "max") {
    char* end = nullptr;
    speed = std::strtod(speed_text->c_str(), &end);
    bool fine = end == speed_text->c_str() + speed_text->size();
    try {
      emulator::RunControl::check_speed(speed);
    } catch (const SetupError&) {
      fine = false;
    }
    if (!fine)
      throw UsageError("--speed takes max, or virtual seconds per wall second from 0.01 to 1000 (1: real time)");
  }
  if ((speed_text || start_paused) && (!virtual_time || external)) {
    throw UsageError("--speed and --paused are for --virtual-time runs (without --external)");
  }
  if (!(outputs.log_period_s > 0)) throw UsageError("--world-log-period takes seconds above 0");
  for (const auto& f : fault_texts) {
    try {
      scenario.faults.push_back(can_nodes::parse_fault(f));
    } catch (const SetupError& e) {
      throw UsageError(std::string("--fault: ") + e.what());
    }
  }
  emulator::SessionOptions options;
  options.realtime = !virtual_time;
  options.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  if (restore_world) options.initial_state = load_world(*restore_world);
  const auto session = [&] {
    try {
      return std::make_unique<emulator::Session>(scenario, options);
    } catch (const SetupError& e) {
      throw UsageError((config ? *config + ": " : std::string()) +
                       (restore_world ? "--restore-world " + *restore_world + ": " : std::string()) + e.what());
    }
  };
  if (!virtual_time) {
    if (outputs.trace || outputs.world_log) {
      throw UsageError(
          "--trace and --world-log are for --virtual-time runs; in real time record the buses with `candump -l "
          "vcan0` or `canhil dump vcan0`");
    }
    if (!(bit_rate >= 10'000 && bit_rate <= 1'000'000)) throw UsageError("--bit-rate takes 10000..1000000 bit/s");
    if (!(rx_buffer_kb >= 16 && rx_buffer_kb <= 65536)) throw UsageError("--rx-buffer-kb takes 16..65536 KiB");
    if (!(priority >= 0 && priority <= 99 && priority == static_cast<int>(priority))) {
      throw UsageError("--priority takes a SCHED_FIFO priority 1..99, or 0 for the normal scheduler");
    }
    options.ftt.bit_rate = static_cast<std::uint32_t>(bit_rate);
    emulator::RealtimeOptions rt;
    rt.receive_buffer_bytes = static_cast<int>(rx_buffer_kb * 1024);
    rt.priority = static_cast<int>(priority);
    RealtimeOutput output;
    output.length = length;
    output.quiet = outputs.quiet;
    output.save_world = outputs.save_world;
    const auto s = session();
    control::Commands commands(*s);
    control::add_save_commands(commands, *s, view.save_dir);
    const auto server = no_control ? nullptr : serve_control(commands, control_path, stdout);
    viewer::LiveFeed feed(*s, commands, nullptr, view.save_dir);
    const auto shown = start_viewer(view, feed, "canhil run", stdout);
    log_commands(commands, shown.get());
    const int status = run_realtime(*s, rt, output);
    feed.set_ended();
    hold_viewer(view, shown.get(), "canhil run", g_stop_run, stdout);
    return status;
  }
  if (std::getenv("RTDB_KEY") == nullptr) {
    // A run of its own: RTDB keys of this process, so it never meets a live robot's database.
    setenv("RTDB_KEY", std::to_string(0x58000000 + ((getpid() & 0xFFFF) << 8)).c_str(), 1);
  }
  if (outputs.world_log) options.world_log_period = from_seconds(outputs.log_period_s);
  if (external) {
    if (outputs.save_world) throw UsageError("--save-world is not available with --external yet");
    try {
      require_told_goal(scenario, false, stderr);
    } catch (const SetupError& e) {  // the scenario to mend, not the command line: no usage
      throw SetupError((config ? *config + ": " : std::string()) + e.what());
    }
    // Before anything is set up: canhil may start itself again, with the shim preloaded.
    const std::string shim = find_timeshim();
    const std::string team_preload = preload_shim_into_self(shim);
    options.external = true;
    if (view.on) {
      std::printf(
          "canhil run: no viewer with --external yet (its server would run under the time shim); watch the "
          "run with --world-log and canhil view\n");
    }
    const auto s = session();
    control::Commands commands(*s);
    const auto server = no_control ? nullptr : serve_control(commands, control_path, stdout);
    ExternalRun run;
    run.length = length;
    run.quiet = outputs.quiet;
    run.trace = outputs.trace;
    run.world_log = outputs.world_log;
    run.log_period_s = outputs.log_period_s;
    run.wait_for = wait_for ? static_cast<std::size_t>(*wait_for) : 0;
    return run_external(*s, run, shim, team_preload);
  }
  const auto s = session();
  control::Commands commands(*s);
  emulator::RunControl clock(options.ftt.elementary_cycle, speed, start_paused);
  control::add_run_commands(commands, clock);
  control::add_save_commands(commands, *s, view.save_dir);
  const auto server = no_control ? nullptr : serve_control(commands, control_path, stdout);
  viewer::LiveFeed feed(*s, commands, &clock, view.save_dir);
  const auto shown = start_viewer(view, feed, "canhil run", stdout);
  log_commands(commands, shown.get());
  if (start_paused)
    std::printf("canhil run: paused at the start (resume or step from the viewer or the control socket)\n");
  const int status = run_virtual(*s, length, outputs, clock, feed);
  hold_viewer(view, shown.get(), "canhil run", g_stop_run, stdout);
  return status;
}

}  // namespace canhil::app
