// `canhil run [--virtual-time] [--config SCENARIO] ...`: a scenario
// (emulator/scenario.hpp; the shipped one-robot scenario by default) as a
// session, driven in virtual time (the whole loop in one process, with a
// trace and a world log) or in real time on SocketCAN next to the team's
// handler and agent. Faults work in both. This file reads the options and
// prints; the run itself is emulator::Session and its drivers.
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "canhil/control/run_commands.hpp"
#include "canhil/control/save_commands.hpp"
#include "canhil/control/unix_server.hpp"
#include "canhil/emulator/run_control.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/external/private_rtdb.hpp"
#include "canhil/external/team_processes.hpp"
#include "canhil/external/time_shim.hpp"
#include "canhil/viewer/live_feed.hpp"
#include "canhil/wire/report.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "log_file.hpp"
#include "play_summary.hpp"
#include "run_external.hpp"
#include "run_realtime.hpp"
#include "run_view.hpp"
#include "stop_signals.hpp"
#include "virtual_loop.hpp"

namespace canhil::app {
namespace {

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
              g_stop ? "stopped" : "done", simulated, wall_s, wall_s > 0 ? simulated / wall_s : 0.0);
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
    if (const wire::WireBus* w = driver.bus(r).wire_bus()) std::fputs(wire::report(*w, "    ").c_str(), stdout);
    if (const laptop::HwComm* hw = driver.handler(r); hw != nullptr && hw->stats().error_frames > 0) {
      const laptop::HwCommStats& h = hw->stats();
      std::printf("    its handler heard %llu error frames: %llu bus-off, %llu restarts; now %s\n",
                  static_cast<unsigned long long>(h.error_frames), static_cast<unsigned long long>(h.bus_offs),
                  static_cast<unsigned long long>(h.restarts), frames::state_name(h.controller));
    }
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
  std::printf("  %s\n", emulator::describe_bus(session.options().bus).c_str());
  std::fflush(stdout);
  stop_on_signals();
  const Nanos total = from_seconds(length.seconds);
  const auto wall_start = std::chrono::steady_clock::now();
  drive_virtual(driver, session, control, total, g_stop, [&] {
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
    const emulator::BusPhysics& bus = session.options().bus;
    if (bus.timed()) {
      std::printf(
          "trace written to %s (candump log, stamped at each frame's end of frame; check it with `canhil "
          "timing --stamps end --bit-rate %u %s`)\n",
          out.trace->c_str(), bus.bit_rate, out.trace->c_str());
    } else {
      std::printf("trace written to %s (candump log; check it with `canhil timing %s`)\n", out.trace->c_str(),
                  out.trace->c_str());
    }
  }
  if (out.save_world) {
    physics::save_state(session.world().save(), *out.save_world);
    std::printf("world saved to %s (start a run from it with --restore-world)\n", out.save_world->c_str());
  }
  if (out.world_log) {
    write_file(*out.world_log, session.world_log(), "world log");
    std::printf("world log written to %s (CSV, one line every %g s)\n", out.world_log->c_str(), out.log_period_s);
  }
  return g_stop ? 130 : 0;
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
void laptop_options(Args& args, emulator::RunOverrides& o) {
  o.rtdb_lib = args.option("--rtdb-lib");
  o.rtdb_items = args.option("--rtdb-items");
  o.rtdb_ini = args.option("--rtdb-ini");
  o.layout = args.option("--layout");
  const auto pman_lib = args.option("--pman-lib");
  const bool no_pman = args.flag("--no-pman");
  if (pman_lib && no_pman) throw UsageError("give --pman-lib PATH or --no-pman, not both");
  if (pman_lib) o.pman = *pman_lib;
  if (no_pman) o.pman = "none";
}

// What `canhil run` was asked: every option read and checked once.
struct RunRequest {
  emulator::RunOverrides overrides;
  std::optional<std::string> config, restore_world, control_path, speed_text;
  VirtualOutputs outputs;
  std::optional<double> wait_for;
  ViewChoice view;
  double speed = 0;  // virtual seconds per wall second; 0: as fast as possible
  bool start_paused = false, no_control = false;
  double rx_buffer_kb = 0, priority = 0;
};

RunRequest read_request(Args& args) {
  RunRequest q;
  emulator::RunOverrides& o = q.overrides;
  const bool external = args.flag("--external");
  const bool virtual_time = args.flag("--virtual-time") || external;  // --external runs in virtual time
  o.mode = external       ? emulator::RunMode::kExternal
           : virtual_time ? emulator::RunMode::kVirtual
                          : emulator::RunMode::kRealtime;
  while (auto p = args.option("--process")) o.processes.push_back(*p);
  o.answer_limit_s = optional_number(args, "--answer-limit");
  q.wait_for = optional_number(args, "--wait-for");
  q.config = args.option("--config");
  q.outputs.trace = args.option("--trace");
  q.outputs.world_log = args.option("--world-log");
  q.outputs.save_world = args.option("--save-world");
  q.restore_world = args.option("--restore-world");
  while (auto f = args.option("--fault")) o.faults.push_back(*f);
  o.seed = seed_option(args);
  q.outputs.quiet = args.flag("--quiet");
  q.control_path = args.option("--control");
  q.view = view_options(args);
  q.speed_text = args.option("--speed");
  q.start_paused = args.flag("--paused");
  q.no_control = args.flag("--no-control");
  if (q.control_path && q.no_control) throw UsageError("give --control PATH or --no-control, not both");
  laptop_options(args, o);
  o.duration_s = optional_number(args, "--duration");
  o.bit_rate = optional_number(args, "--bit-rate");
  q.rx_buffer_kb = number_option(args, "--rx-buffer-kb", 1024);
  q.priority = number_option(args, "--priority", 40);
  q.outputs.log_period_s = number_option(args, "--world-log-period", 0.05);
  if (const auto k = optional_number(args, "--kick-power")) o.kick_power = static_cast<int>(*k);
  if (args.positionals().size() != 1) throw UsageError("run takes no other arguments");
  if (!external && (!o.processes.empty() || o.answer_limit_s || q.wait_for)) {
    throw UsageError("--process, --answer-limit and --wait-for are for runs with --external");
  }
  if (q.wait_for && !(*q.wait_for >= 1 && *q.wait_for <= 64 && *q.wait_for == static_cast<int>(*q.wait_for))) {
    throw UsageError("--wait-for takes a number of processes, 1..64");
  }
  if (q.speed_text && *q.speed_text != "max") {
    char* end = nullptr;
    q.speed = std::strtod(q.speed_text->c_str(), &end);
    bool fine = end == q.speed_text->c_str() + q.speed_text->size();
    try {
      emulator::RunControl::check_speed(q.speed);
    } catch (const SetupError&) {
      fine = false;
    }
    if (!fine)
      throw UsageError("--speed takes max, or virtual seconds per wall second from 0.01 to 1000 (1: real time)");
  }
  if ((q.speed_text || q.start_paused) && (!virtual_time || external)) {
    throw UsageError("--speed and --paused are for --virtual-time runs (without --external)");
  }
  if (!(q.outputs.log_period_s > 0)) throw UsageError("--world-log-period takes seconds above 0");
  if (!virtual_time) {
    if (q.outputs.trace || q.outputs.world_log) {
      throw UsageError(
          "--trace and --world-log are for --virtual-time runs; in real time record the buses with `candump -l "
          "vcan0` or `canhil dump vcan0`");
    }
    if (!(q.rx_buffer_kb >= 16 && q.rx_buffer_kb <= 65536)) throw UsageError("--rx-buffer-kb takes 16..65536 KiB");
    if (!(q.priority >= 0 && q.priority <= 99 && q.priority == static_cast<int>(q.priority))) {
      throw UsageError("--priority takes a SCHED_FIFO priority 1..99, or 0 for the normal scheduler");
    }
  }
  if (external && q.outputs.save_world) throw UsageError("--save-world is not available with --external yet");
  return q;
}

// The run's plan: the scenario with the request's overrides, resolved once.
emulator::RunPlan make_plan(const RunRequest& q, const std::optional<std::string>& dbc) {
  emulator::SessionOptions options;
  options.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  if (q.restore_world) options.initial_state = load_world(*q.restore_world);
  if (q.overrides.mode != emulator::RunMode::kRealtime && q.outputs.world_log) {
    options.world_log_period = from_seconds(q.outputs.log_period_s);
  }
  try {
    return emulator::plan_run(q.config ? std::optional<std::filesystem::path>(*q.config) : std::nullopt, q.overrides,
                              std::move(options));
  } catch (const emulator::OverrideError& e) {
    throw UsageError(e.what());
  }
}

// The session and what serves it, the same for every mode: the commands (the
// run's clock's, where it has one; saving, except with --external), the
// control socket, and, except with --external, the live feed, the viewer and
// the log of what they did.
struct RunSetup {
  std::unique_ptr<emulator::Session> session;
  std::unique_ptr<control::Commands> commands;
  std::unique_ptr<control::UnixServer> server;
  std::unique_ptr<viewer::LiveFeed> feed;
  std::unique_ptr<viewer::Server> shown;
};

RunSetup set_up(emulator::RunPlan plan, const RunRequest& q, emulator::RunControl* clock) {
  RunSetup s;
  try {
    s.session = std::make_unique<emulator::Session>(std::move(plan));
  } catch (const SetupError& e) {
    throw UsageError((q.config ? *q.config + ": " : std::string()) +
                     (q.restore_world ? "--restore-world " + *q.restore_world + ": " : std::string()) + e.what());
  }
  const bool external = q.overrides.mode == emulator::RunMode::kExternal;
  s.commands = std::make_unique<control::Commands>(*s.session);
  if (clock != nullptr) control::add_run_commands(*s.commands, *clock);
  if (!external) control::add_save_commands(*s.commands, *s.session, q.view.save_dir);
  if (!q.no_control) s.server = serve_control(*s.commands, q.control_path, stdout);
  if (external) return s;
  s.feed = std::make_unique<viewer::LiveFeed>(*s.session, *s.commands, clock, q.view.save_dir);
  s.shown = start_viewer(q.view, *s.feed, "canhil run", stdout);
  log_commands(*s.commands, s.shown.get());
  return s;
}

}  // namespace

int run_run(Args& args, const std::optional<std::string>& dbc) {
  const RunRequest q = read_request(args);
  const emulator::RunMode mode = q.overrides.mode;
  // With the team's processes: canhil under the time shim before anything is
  // planned or set up (it may start itself again, and then plans once).
  std::string shim, team_preload;
  if (mode == emulator::RunMode::kExternal) {
    shim = external::find_timeshim();
    team_preload = external::preload_shim_into_self(shim);
  }
  // A run of its own: RTDB keys of this process, so it never meets a live robot's database.
  if (mode != emulator::RunMode::kRealtime) external::use_private_rtdb_keys(external::kRunKeyPrefix);
  emulator::RunPlan plan = make_plan(q, dbc);
  if (mode == emulator::RunMode::kRealtime) {
    emulator::RealtimeOptions rt;
    rt.receive_buffer_bytes = static_cast<int>(q.rx_buffer_kb * 1024);
    rt.priority = static_cast<int>(q.priority);
    RealtimeOutput output;
    output.length = plan.length;
    output.quiet = q.outputs.quiet;
    output.save_world = q.outputs.save_world;
    const RunSetup s = set_up(std::move(plan), q, nullptr);
    const int status = run_realtime(*s.session, rt, output);
    s.feed->set_ended();
    hold_viewer(q.view, s.shown.get(), "canhil run", g_stop, stdout);
    return status;
  }
  if (mode == emulator::RunMode::kExternal) {
    try {
      external::require_told_goal(plan.scenario, false, stderr);
    } catch (const SetupError& e) {  // the scenario to mend, not the command line: no usage
      throw SetupError((q.config ? *q.config + ": " : std::string()) + e.what());
    }
    if (q.view.on) {
      std::printf(
          "canhil run: no viewer with --external yet (its server would run under the time shim); watch the "
          "run with --world-log and canhil view\n");
    }
    ExternalRequest run;
    run.length = plan.length;
    run.quiet = q.outputs.quiet;
    run.trace = q.outputs.trace;
    run.world_log = q.outputs.world_log;
    run.log_period_s = q.outputs.log_period_s;
    run.wait_for = q.wait_for ? static_cast<std::size_t>(*q.wait_for) : 0;
    const RunSetup s = set_up(std::move(plan), q, nullptr);
    return run_external(*s.session, run, shim, team_preload);
  }
  emulator::RunControl clock(plan.options.ftt.elementary_cycle, q.speed, q.start_paused);
  const emulator::RunLength length = plan.length;
  const RunSetup s = set_up(std::move(plan), q, &clock);
  if (q.start_paused)
    std::printf("canhil run: paused at the start (resume or step from the viewer or the control socket)\n");
  const int status = run_virtual(*s.session, length, q.outputs, clock, *s.feed);
  hold_viewer(q.view, s.shown.get(), "canhil run", g_stop, stdout);
  return status;
}

}  // namespace canhil::app
