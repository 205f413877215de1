// `canhil run --config SCENARIO` in real time: every robot of the scenario with
// its emulated nodes on its SocketCAN interface, the physics locked to the wall
// clock, the emulated vision written into each robot's agent's RTDB (with
// DB_signal_frame), faults on the nodes' frames. The team's own handler and
// agent (or canhil-hwcomm and canhil-agent) run next to it, one per robot with
// AGENT set. It reports when it falls behind, an interface going down and up,
// goals, and ends (duration, Ctrl-C) with a summary. The FTT masters run on a
// thread of their own at the highest priority, the other nodes on this one,
// the physics (with vision) on a third, so that neither a physics step nor
// the slaves' work delays a trigger message (emulator/realtime_physics.hpp).
#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/realtime.hpp"
#include "canhil/emulator/realtime_physics.hpp"
#include "canhil/emulator/robot_nodes.hpp"
#include "canhil/emulator/shared_robot_io.hpp"
#include "canhil/emulator/virtual_run.hpp"
#include "canhil/rtdb/rtdb.h"
#include "canhil/vision_emu/runner.hpp"
#include "fifo_scheduling.hpp"
#include "realtime_run.hpp"
#include "wall_waiter.hpp"

namespace canhil::app {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void stop_realtime(int) { g_stop = true; }

struct Robot {
  std::unique_ptr<emulator::SharedRobotIo> io;
  std::vector<can_nodes::SocketCanBus*> sockets;
  std::unique_ptr<emulator::RobotNodes> nodes;
  std::unique_ptr<can_nodes::FaultInjector> faults;
  can_nodes::BusState state = can_nodes::BusState::kUp;
};

// A network device with a `device` link is hardware (a CAN adapter); vcan has none.
bool is_virtual_interface(const std::string& iface) {
  return !std::filesystem::exists("/sys/class/net/" + iface + "/device");
}

}  // namespace

int run_realtime(const emulator::Scenario& sc, const RealtimeOptions& opt) {
  struct Output {
    FILE* file;
    ~Output() {
      if (file != stdout) std::fclose(file);
    }
  } output{opt.silent ? std::fopen("/dev/null", "w") : stdout};
  if (output.file == nullptr) output.file = stdout;
  FILE* out = output.file;
  physics::World world(sc.world);
  if (opt.initial_state) {
    try {
      world.restore(*opt.initial_state);
    } catch (const SetupError& e) {
      throw SetupError(std::string("the saved world does not fit the scenario: ") + e.what());
    }
  }
  const std::size_t n = sc.world.robots.size();
  can_nodes::FttConfig ftt;
  ftt.bit_rate = opt.bit_rate;
  const can_nodes::NodeParams params = emulator::node_params_for(sc.world.robot, ftt);
  const can_nodes::WallClock clock;
  const auto ec = params.ftt.elementary_cycle;
  const Nanos start = (clock.now() / ec + 10) * ec;  // on a whole EC, a little ahead
  std::vector<Robot> robots(n);
  std::vector<int> fds;
  const bool error_frames = std::any_of(sc.faults.begin(), sc.faults.end(), [](const can_nodes::FaultRule& f) {
    return f.kind == can_nodes::FaultKind::kErrorFrame;
  });
  for (std::size_t r = 0; r < n && error_frames; ++r) {
    if (!is_virtual_interface(sc.interfaces[r])) {
      // A controller cannot be told to send an error frame: the flag would be masked and a data frame go out.
      throw SetupError("error-frame faults need a virtual interface; " + sc.interfaces[r] +
                                  " is a CAN adapter. Use a bus disturber on a real bus, or run on vcan");
    }
  }
  for (std::size_t r = 0; r < n; ++r) {
    Robot& robot = robots[r];
    robot.io = std::make_unique<emulator::SharedRobotIo>(world.robot(r));
    const std::string& iface = sc.interfaces[r];
    robot.nodes = std::make_unique<emulator::RobotNodes>(
        opt.messages, params, *robot.io,
        [&](const std::string&) {
          can_nodes::SocketCanOptions socket_options;
          socket_options.receive_buffer_bytes = opt.receive_buffer_bytes;
          auto bus = can_nodes::SocketCanBus::open(iface, socket_options);
          robot.sockets.push_back(bus.get());
          return std::unique_ptr<can_nodes::Bus>(std::move(bus));
        },
        start);
    if (robot.sockets.front()->state() != can_nodes::BusState::kUp) {
      throw SetupError(iface + " is down; bring it up with `ip link set " + iface + " up`");
    }
    for (std::size_t k = 1; k < robot.sockets.size(); ++k) fds.push_back(robot.sockets[k]->fd());  // not the master's
    if (!sc.faults.empty()) {
      std::vector<std::string> names;
      for (can_nodes::Node* node : robot.nodes->nodes()) names.push_back(node->name());
      robot.faults =
          std::make_unique<can_nodes::FaultInjector>(sc.faults, opt.messages, names, sc.seed + r, opt.bit_rate);
      robot.faults->start_at(start);  // rule times count from the run's start, not the clock's epoch
      for (can_nodes::Node* node : robot.nodes->nodes()) node->set_fault_hook(robot.faults.get());
    }
  }
  if (DB_init_all(0) != 0) throw SetupError("cannot attach to the RTDB (see above)");
  struct RtdbGuard {
    ~RtdbGuard() { DB_free_all(0); }
  } rtdb_guard;
  std::vector<vision_emu::Vision> vision;
  for (std::size_t r = 0; r < n; ++r) vision.emplace_back(opt.vision, world.markings());
  vision_emu::VisionRunner vision_runner(std::move(vision), vision_emu::rtdb_sink(sc.agents));
  emulator::GoalWatcher goals(sc.world);
  std::mutex goal_mutex;
  std::vector<Nanos> goal_times;  // copied out of the physics thread

  // Threads: this one runs the nodes (but the masters, below) on the sockets
  // and never waits for a physics step; the physics (with vision, goals and
  // battery faults) steps on its own, exchanging commands and sensor values
  // through SharedRobotIo.
  WallWaiter waiter(fds);
  emulator::Realtime loop(clock, nullptr, [&](Nanos d) { waiter.wait(d); });
  // The FTT masters on a third thread, above the other nodes: a trigger message
  // goes out at its EC boundary whatever the slaves are busy with (on a robot
  // the master is a microcontroller of its own too). The masters only send.
  emulator::Realtime masters(clock, nullptr, [](Nanos d) { can_nodes::WallClock::sleep_until(d); });
  std::vector<emulator::SharedRobotIo*> shared;
  for (Robot& robot : robots) {
    for (can_nodes::Node* node : robot.nodes->nodes()) {
      if (node == &robot.nodes->node(emulator::NodeId::kMaster)) {
        masters.add(*node);
      } else {
        loop.add(*node);
      }
    }
    shared.push_back(robot.io.get());
  }
  emulator::RealtimePhysics physics(world, shared);
  physics.on_step([&](Nanos now) {
    for (std::size_t r = 0; r < n; ++r) {
      if (robots[r].faults) world.robot(r).drain(robots[r].faults->battery_drain_until(now));
    }
    vision_runner.on_step(world);
    const std::size_t before = goals.goals().size();
    goals.step(world, now);
    if (goals.goals().size() != before) {
      const std::lock_guard lock(goal_mutex);
      goal_times.push_back(goals.goals().back().time);
    }
  });

  std::signal(SIGINT, stop_realtime);
  std::signal(SIGTERM, stop_realtime);
  char length[32] = "until Ctrl-C";
  if (opt.duration_s > 0) std::snprintf(length, sizeof length, "%g s", opt.duration_s);
  std::fprintf(out, "canhil run: %zu robot(s), real time, %s, seed %llu, %zu fault rule(s)\n", n, length,
               static_cast<unsigned long long>(sc.seed), sc.faults.size());
  for (std::size_t r = 0; r < n; ++r) {
    std::fprintf(out, "  robot %zu on %s for agent %d (start your handler and agent with AGENT=%d)\n", r,
                 sc.interfaces[r].c_str(), sc.agents[r], sc.agents[r]);
  }
  std::fflush(out);
  const Nanos end =
      opt.duration_s > 0
          ? start + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(opt.duration_s))
          : kNever;
  Nanos next_report = start + std::chrono::seconds(1);
  std::size_t goals_reported = 0;
  const MemoryLock memory(opt.priority > 0);
  physics.start(start);  // before the priority: the physics thread keeps the normal scheduler
  struct MasterThread {  // joined on every way out, an exception included
    std::atomic<bool> stop{false};
    std::thread thread;
    void join() {
      stop = true;
      if (thread.joinable()) thread.join();
    }
    ~MasterThread() { join(); }
  } master;
  master.thread = std::thread([&] {
    const FifoScheduling fifo(opt.priority > 0 ? std::min(99, opt.priority + 1) : 0);
    masters.run_until(kNever, master.stop);
  });
  const FifoScheduling fifo(opt.priority);
  if (!fifo.problem.empty()) std::fprintf(out, "canhil run: %s\n", fifo.problem.c_str());
  while (!g_stop && clock.now() < end) {
    loop.run_until(std::min(end, clock.now() + std::chrono::milliseconds(200)), g_stop);
    for (std::size_t r = 0; r < n; ++r) {
      const can_nodes::BusState state = robots[r].sockets.back()->refresh_state();  // SysMon's: this thread's
      if (state != robots[r].state) {
        std::fprintf(out, "canhil run: %s is %s\n", sc.interfaces[r].c_str(), bus_state_text(state));
        robots[r].state = state;
      }
    }
    {
      const std::lock_guard lock(goal_mutex);
      for (; goals_reported < goal_times.size(); ++goals_reported) {
        std::fprintf(out, "  GOAL at %.2f s\n",
                     std::chrono::duration<double>(goal_times[goals_reported] - start).count());
      }
    }
    if (!opt.quiet && clock.now() >= next_report) {
      const emulator::RealtimePhysics::View view = physics.view();
      std::fprintf(out, "  t=%5.1f s  ball (%6.2f, %5.2f)", std::chrono::duration<double>(clock.now() - start).count(),
                   view.ball.x(), view.ball.y());
      for (std::size_t r = 0; r < n; ++r) {
        std::fprintf(out, "  %s (%5.2f, %5.2f)", sc.interfaces[r].c_str(), view.robots[r].x_m, view.robots[r].y_m);
      }
      std::fprintf(out, "  late steps %llu\n", static_cast<unsigned long long>(physics.stats().late_steps));
      next_report += std::chrono::seconds(1);
    }
    std::fflush(out);
  }
  master.join();
  physics.stop();  // the world is this thread's again
  // What is still queued is read and counted, so the summary covers every frame
  // that reached the emulator (bounded: a flood may still be going on).
  for (Robot& robot : robots) {
    for (can_nodes::Node* node : robot.nodes->nodes()) node->poll(std::size_t{1} << 16);
  }
  const emulator::RealtimeStats st = physics.stats();
  const Eigen::Vector3d b = world.ball_position();
  std::fprintf(out,
               "canhil run: %s after %.2f s; physics steps %llu, late %llu, skipped %llu, worst lateness %.1f ms\n",
               g_stop ? "stopped" : "done", std::chrono::duration<double>(clock.now() - start).count(),
               static_cast<unsigned long long>(st.physics_steps), static_cast<unsigned long long>(st.late_steps),
               static_cast<unsigned long long>(st.skipped_steps),
               std::chrono::duration<double, std::milli>(st.worst_lateness).count());
  std::fprintf(out, "  ball at (%.2f, %.2f); %zu goal(s)\n", b.x(), b.y(), goals.goals().size());
  if (opt.save_world) {
    physics::save_state(world.save(), *opt.save_world);
    std::fprintf(out, "  world saved to %s (start a run from it with --restore-world)\n", opt.save_world->c_str());
  }
  for (std::size_t r = 0; r < n; ++r) {
    const kinematics::Pose p = world.robot(r).pose();
    const auto& tm = robots[r].nodes->node(emulator::NodeId::kMaster).counters();
    const physics::Robot& robot = world.robot(r);
    std::fprintf(out, "  %s agent %d: at (%.2f, %.2f), %llu TMs sent, %llu bad frames, 24 V pack %.1f V (%.0f %%)\n",
                 sc.interfaces[r].c_str(), sc.agents[r], p.x_m, p.y_m, static_cast<unsigned long long>(tm.sent),
                 static_cast<unsigned long long>(robots[r].nodes->bad_frames()), robot.battery().power24_v,
                 100 * robot.charge()[2]);
    std::fprintf(out, "    bus: %s\n", emulator::describe(robots[r].nodes->bus_report()).c_str());
    if (robots[r].faults) {
      for (const auto& c : robots[r].faults->counts()) {
        std::fprintf(out, "    fault %-24s %s\n", c.rule.c_str(), can_nodes::describe(c).c_str());
      }
    }
  }
  return g_stop ? 130 : 0;
}

}  // namespace canhil::app
