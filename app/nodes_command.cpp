// `canhil nodes --iface IFACE`: one robot's emulated node set with its physics,
// in real time on a SocketCAN interface, so any laptop-side program can talk
// to it. The wall clock is read here (and only in app/).
#include <poll.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <vector>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/realtime.hpp"
#include "canhil/emulator/robot_nodes.hpp"
#include "canhil/physics/config.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "wall_waiter.hpp"

namespace canhil::app {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void stop_on_signal(int) { g_stop = true; }

}  // namespace

int run_nodes(Args& args, const std::optional<std::string>& dbc) {
  const auto iface = args.option("--iface");
  const auto config = args.option("--config");
  const double duration_s = number_option(args, "--duration", 0);
  const double ec_ms = number_option(args, "--ec-ms", 10);
  const double bit_rate = number_option(args, "--bit-rate", 1'000'000);
  const bool quiet = args.flag("--quiet");
  if (args.positionals().size() != 1) throw UsageError("nodes takes no other arguments");
  if (!iface) throw UsageError("nodes needs --iface IFACE (e.g. --iface vcan0)");

  auto set = frames::MessageSet::create(load_chosen_dbc(dbc));
  physics::WorldParams wp = config ? physics::load_world_params(*config) : physics::WorldParams{};
  // Without robots in the file: one robot a metre behind the ball, facing it (+x).
  if (wp.robots.empty()) wp.robots.push_back(physics::Placement{-1.0, 0, -90});
  physics::World world(wp);
  emulator::PhysicsRobotIo io(world.robot(0));
  can_nodes::FttConfig ftt;
  ftt.elementary_cycle = std::chrono::duration_cast<Nanos>(std::chrono::duration<double, std::milli>(ec_ms));
  ftt.bit_rate = static_cast<std::uint32_t>(bit_rate);
  const can_nodes::NodeParams params = emulator::node_params_for(wp.robot, ftt);

  std::vector<can_nodes::SocketCanBus*> sockets;
  const can_nodes::WallClock clock;
  // Start on a whole EC of the wall clock, a little ahead, so TMs are easy to read in traces.
  const auto ec = params.ftt.elementary_cycle;
  const Nanos start = (clock.now() / ec + 10) * ec;
  emulator::RobotNodes nodes(
      set, params, io,
      [&](const std::string&) {
        auto bus = can_nodes::SocketCanBus::open(*iface);
        sockets.push_back(bus.get());
        return std::unique_ptr<can_nodes::Bus>(std::move(bus));
      },
      start);
  if (sockets.front()->state() != can_nodes::BusState::kUp) {
    throw SetupError(*iface + " is down; bring it up with `ip link set " + *iface + " up`");
  }
  std::vector<int> fds;
  fds.reserve(sockets.size());
  for (auto* s : sockets) fds.push_back(s->fd());
  WallWaiter waiter(fds);
  emulator::Realtime loop(clock, &world, [&](Nanos d) { waiter.wait(d); });
  for (can_nodes::Node* n : nodes.nodes()) loop.add(*n);

  std::signal(SIGINT, stop_on_signal);
  std::signal(SIGTERM, stop_on_signal);
  std::printf(
      "canhil nodes: robot on %s: FTT master (EC %.1f ms, %u bit/s), Pic_base, Motor1-3, Pic_odom, Compass, "
      "SysMon; physics every %.0f ms. Ctrl-C stops.\n",
      iface->c_str(), ec_ms, ftt.bit_rate, wp.simulation.step_s * 1000);
  std::fflush(stdout);

  const Nanos end =
      duration_s > 0 ? start + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(duration_s))
                     : kNever;
  can_nodes::BusState last_state = can_nodes::BusState::kUp;
  Nanos next_report = start + std::chrono::seconds(5);
  while (!g_stop && clock.now() < end) {
    const Nanos slice = std::min(end, clock.now() + std::chrono::seconds(1));
    loop.run_until(slice, g_stop);
    const can_nodes::BusState state = sockets.front()->refresh_state();
    if (state != last_state) {
      std::printf("canhil nodes: %s is %s\n", iface->c_str(), bus_state_text(state));
      std::fflush(stdout);
      last_state = state;
    }
    if (!quiet && clock.now() >= next_report) {
      const kinematics::Pose pose = world.robot(0).pose();
      const std::uint64_t bad = nodes.bad_frames();
      std::printf("canhil nodes: %.0f s, %llu TMs, robot at (%.2f, %.2f) m, %llu bad frames, %llu late steps\n",
                  std::chrono::duration<double>(clock.now() - start).count(),
                  static_cast<unsigned long long>(nodes.node(emulator::NodeId::kMaster).counters().sent), pose.x_m,
                  pose.y_m, static_cast<unsigned long long>(bad),
                  static_cast<unsigned long long>(loop.stats().late_steps));
      std::fflush(stdout);
      next_report += std::chrono::seconds(5);
    }
  }

  const emulator::RealtimeStats& st = loop.stats();
  std::printf("\ncanhil nodes: summary after %.1f s on %s\n",
              std::chrono::duration<double>(clock.now() - start).count(), iface->c_str());
  std::printf("  %-12s %10s %10s %10s %12s %10s\n", "node", "sent", "received", "bad", "send failed", "dropped");
  for (std::size_t i = 0; i < emulator::kNodeCount; ++i) {
    const auto& c = nodes.node(static_cast<emulator::NodeId>(i)).counters();
    std::printf("  %-12s %10llu %10llu %10llu %12llu %10llu\n", emulator::node_name(static_cast<emulator::NodeId>(i)),
                static_cast<unsigned long long>(c.sent), static_cast<unsigned long long>(c.received),
                static_cast<unsigned long long>(c.bad_frames()), static_cast<unsigned long long>(c.send_failed),
                static_cast<unsigned long long>(sockets[i]->stats().rx_overflow));
  }
  const kinematics::Pose pose = world.robot(0).pose();
  std::printf("  physics: %llu steps, %llu late (worst %.2f ms), %llu skipped; robot at (%.3f, %.3f) m, %.1f deg\n",
              static_cast<unsigned long long>(st.physics_steps), static_cast<unsigned long long>(st.late_steps),
              std::chrono::duration<double, std::milli>(st.worst_lateness).count(),
              static_cast<unsigned long long>(st.skipped_steps), pose.x_m, pose.y_m,
              pose.heading_rad * 180 / 3.14159265);
  return 0;
}

}  // namespace canhil::app
