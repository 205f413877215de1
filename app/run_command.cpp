// `canhil run [--virtual-time] [--config SCENARIO] ...`: a scenario file
// (emulator/scenario.hpp) run either in virtual time, the whole loop in one
// process (emulator/virtual_run.hpp) with a trace and a world log, or in real
// time on SocketCAN next to the team's handler and agent (realtime_run.cpp).
// Faults work in both.
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/virtual_run.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "realtime_run.hpp"

namespace canhil::app {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void stop_run(int) { g_stop = true; }

void write_file(const std::string& path, const std::string& text, const char* what) {
  std::ofstream out(path);
  out << text;
  if (!out) throw UsageError("cannot write the " + std::string(what) + " to " + path);
}

// A saved world (--restore-world), or a usage error naming the file and what is wrong.
physics::WorldState load_world(const std::string& path) {
  try {
    return physics::load_state(path);
  } catch (const std::exception& e) {
    throw UsageError("--restore-world " + path + ": " + e.what() +
                     "; give a file written by `canhil run --save-world FILE`");
  }
}

void save_world_to(const physics::WorldState& state, const std::string& path) {
  try {
    physics::save_state(state, path);
  } catch (const std::exception& e) {
    throw UsageError("--save-world " + path + ": " + e.what());
  }
}

}  // namespace

int run_run(Args& args, const std::optional<std::string>& dbc) {
  const bool virtual_time = args.flag("--virtual-time");
  const auto config = args.option("--config");
  const auto trace = args.option("--trace");
  const auto world_log = args.option("--world-log");
  const auto save_world = args.option("--save-world");
  const auto restore_world = args.option("--restore-world");
  std::vector<std::string> fault_texts;
  while (auto f = args.option("--fault")) fault_texts.push_back(*f);
  const auto seed_text = args.option("--seed");
  const bool quiet = args.flag("--quiet");
  emulator::Scenario scenario;
  if (config) {
    scenario = emulator::load_scenario(*config);
  } else {
    scenario.world.robots = {physics::Placement{-3.0, 0.0, -90}};  // facing the opponent goal (+x)
    scenario.world.ball_start = {-1.0, 1.0, scenario.world.ball.radius_m};
    scenario.interfaces = {"vcan0"};
    scenario.agents = {1};
    scenario.duration_s = 8;
  }
  const std::optional<double> duration_given = optional_number(args, "--duration");
  const double bit_rate = number_option(args, "--bit-rate", 1'000'000);
  const double rx_buffer_kb = number_option(args, "--rx-buffer-kb", 1024);
  const double priority = number_option(args, "--priority", 40);
  const double duration = duration_given.value_or(scenario.duration_s);
  const double log_period = number_option(args, "--world-log-period", 0.05);
  scenario.kick_power = static_cast<int>(number_option(args, "--kick-power", scenario.kick_power));
  if (seed_text) {
    try {
      std::size_t used = 0;
      scenario.seed = std::stoull(*seed_text, &used);
      if (used != seed_text->size() || (*seed_text)[0] == '-') throw std::invalid_argument(*seed_text);
    } catch (const std::exception&) {
      throw UsageError("--seed takes a whole number, 0 or more, got '" + *seed_text + "'");
    }
  }
  if (args.positionals().size() != 1) throw UsageError("run takes no other arguments");
  if (!(duration > 0)) throw UsageError("--duration takes seconds above 0");
  if (!(log_period > 0)) throw UsageError("--world-log-period takes seconds above 0");
  for (const auto& f : fault_texts) {
    try {
      scenario.faults.push_back(can_nodes::parse_fault(f));
    } catch (const SetupError& e) {
      throw UsageError(std::string("--fault: ") + e.what());
    }
  }
  if (!virtual_time) {
    if (trace || world_log) {
      throw UsageError(
          "--trace and --world-log are for --virtual-time runs; in real time record the buses with `candump -l "
          "vcan0` or `canhil dump vcan0`");
    }
    if (!(bit_rate >= 10'000 && bit_rate <= 1'000'000)) throw UsageError("--bit-rate takes 10000..1000000 bit/s");
    if (!(rx_buffer_kb >= 16 && rx_buffer_kb <= 65536)) throw UsageError("--rx-buffer-kb takes 16..65536 KiB");
    if (!(priority >= 0 && priority <= 99 && priority == static_cast<int>(priority))) {
      throw UsageError("--priority takes a SCHED_FIFO priority 1..99, or 0 for the normal scheduler");
    }
    RealtimeOptions opt;
    opt.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
    opt.duration_s = duration_given.value_or(0);  // none: until Ctrl-C
    opt.bit_rate = static_cast<std::uint32_t>(bit_rate);
    opt.receive_buffer_bytes = static_cast<int>(rx_buffer_kb * 1024);
    opt.priority = static_cast<int>(priority);
    if (restore_world) opt.initial_state = load_world(*restore_world);
    opt.save_world = save_world;
    opt.quiet = quiet;
    return run_realtime(scenario, opt);
  }
  if (std::getenv("RTDB_KEY") == nullptr) {
    // A run of its own: RTDB keys of this process, so it never meets a live robot's database.
    setenv("RTDB_KEY", std::to_string(0x58000000 + ((getpid() & 0xFFFF) << 8)).c_str(), 1);
  }
  emulator::VirtualRunConfig cfg =
      emulator::virtual_run_config(scenario, frames::MessageSet::create(load_chosen_dbc(dbc)));
  cfg.record_trace = trace.has_value();  // a long run without --trace keeps no frames
  if (restore_world) cfg.initial_state = load_world(*restore_world);
  if (world_log)
    cfg.world_log_period = std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(log_period));
  std::unique_ptr<emulator::VirtualRun> run;
  try {
    run = std::make_unique<emulator::VirtualRun>(cfg);
  } catch (const SetupError& e) {
    const std::string where =
        restore_world ? "--restore-world " + *restore_world + " does not fit the scenario: " : std::string();
    throw UsageError((config ? *config + ": " : std::string()) + where + e.what());
  }
  std::printf("canhil run: %zu robot(s), virtual time, %g s, seed %llu, %zu fault rule(s)\n", cfg.world.robots.size(),
              duration, static_cast<unsigned long long>(cfg.seed), cfg.faults.size());
  std::signal(SIGINT, stop_run);
  std::signal(SIGTERM, stop_run);
  const auto step = std::chrono::seconds(1);
  const auto total = std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(duration));
  const auto wall_start = std::chrono::steady_clock::now();
  while (run->now() < total && !g_stop) {
    run->run_for(std::min<Nanos>(step, total - run->now()));
    if (quiet) continue;
    const Eigen::Vector3d b = run->world().ball_position();
    const auto o = run->outcomes();
    std::printf("  t=%5.1f s  ball (%6.2f, %5.2f)", std::chrono::duration<double>(run->now()).count(), b.x(), b.y());
    for (std::size_t r = 0; r < o.size(); ++r) {
      std::printf("  %s (%5.2f, %5.2f) kicks %d", cfg.interfaces[r].c_str(), o[r].pose.x_m, o[r].pose.y_m, o[r].kicks);
    }
    std::printf("\n");
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double simulated = std::chrono::duration<double>(run->now()).count();
  if (trace) {
    write_file(*trace, run->trace(), "trace");
    std::printf("trace written to %s (candump log; check it with `canhil timing %s`)\n", trace->c_str(),
                trace->c_str());
  }
  if (save_world) {
    save_world_to(run->world().save(), *save_world);
    std::printf("world saved to %s (start a run from it with --restore-world)\n", save_world->c_str());
  }
  if (world_log) {
    write_file(*world_log, run->world_log(), "world log");
    std::printf("world log written to %s (CSV, one line every %g s)\n", world_log->c_str(), log_period);
  }
  // The summary.
  std::printf("canhil run: %s after %.2f s of virtual time in %.2f s of wall time (%.0fx real time)\n",
              g_stop ? "stopped" : "done", simulated, wall, wall > 0 ? simulated / wall : 0.0);
  const Eigen::Vector3d b = run->world().ball_position();
  std::printf("  ball at (%.2f, %.2f)\n", b.x(), b.y());
  for (const emulator::Goal& g : run->goals()) {
    std::printf("  GOAL at %.2f s in the %s goal\n", std::chrono::duration<double>(g.time).count(),
                g.positive_x ? "+x (opponent)" : "-x (own)");
  }
  const auto outcomes = run->outcomes();
  for (std::size_t r = 0; r < outcomes.size(); ++r) {
    const auto& o = outcomes[r];
    std::printf("  %s agent %d: at (%.2f, %.2f), %d kick(s), %llu frames, %llu bad, 24 V pack %.1f V (%.0f %%)\n",
                cfg.interfaces[r].c_str(), cfg.agents[r], o.pose.x_m, o.pose.y_m, o.kicks,
                static_cast<unsigned long long>(o.frames), static_cast<unsigned long long>(o.bad_frames),
                o.battery.power24_v, 100 * o.charge[2]);
  }
  for (const auto& c : run->fault_counts()) {
    std::printf("  fault %-24s %s\n", c.rule.c_str(), can_nodes::describe(c).c_str());
  }
  return g_stop ? 130 : 0;
}

}  // namespace canhil::app
