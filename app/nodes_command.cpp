// `canhil nodes --iface IFACE`: one robot's emulated node set with its physics,
// in real time on a SocketCAN interface, so any laptop-side program can talk
// to it: a session of one robot without vision or RTDB, on the real-time driver.
#include <algorithm>
#include <atomic>
#include <cstdio>

#include "canhil/emulator/realtime_driver.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

// --emulate Motor1,Motor2,Motor3: the nodes canhil plays; the others are real boards on the bus.
can_nodes::NodeSet parse_emulate(const std::string& text) {
  can_nodes::NodeSet set;
  std::size_t from = 0;
  while (from <= text.size()) {
    const std::size_t comma = std::min(text.find(',', from), text.size());
    const std::string name = text.substr(from, comma - from);
    const auto id = can_nodes::node_by_name(name);
    if (!id)
      throw UsageError("--emulate: \"" + name + "\" is not a node; the nodes are " + can_nodes::node_name_list());
    if (set.contains(*id)) throw UsageError("--emulate: " + name + " appears twice");
    set.insert(*id);
    from = comma + 1;
  }
  return set;
}

}  // namespace

int run_nodes(Args& args, const std::optional<std::string>& dbc) {
  const auto iface = args.option("--iface");
  const auto config = args.option("--config");
  const double duration_s = number_option(args, "--duration", 0);
  const double ec_ms = number_option(args, "--ec-ms", 10);
  const double bit_rate = number_option(args, "--bit-rate", 1'000'000);
  const bool quiet = args.flag("--quiet");
  const auto emulate = args.option("--emulate");
  if (args.positionals().size() != 1) throw UsageError("nodes takes no other arguments");
  if (!iface) throw UsageError("nodes needs --iface IFACE (e.g. --iface vcan0)");
  if (!(ec_ms > 0)) throw UsageError("--ec-ms takes milliseconds above 0");

  // The world file's first robot (kDefaultPlacement without one) on the interface.
  const emulator::Scenario scenario = config ? emulator::read_scenario(*config) : emulator::Scenario{};
  emulator::RunOverrides one_robot;
  one_robot.robots = 1;
  one_robot.interfaces = {*iface};
  one_robot.agents = {emulator::kFirstAgent};
  if (emulate) one_robot.emulate = {parse_emulate(*emulate)};
  emulator::SessionOptions options;
  options.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  options.ftt.elementary_cycle = from_ms(ec_ms);
  options.ftt.bit_rate = static_cast<std::uint32_t>(bit_rate);
  options.vision_on = false;
  emulator::Session session(emulator::plan_run(scenario, options, one_robot));
  emulator::RealtimeOptions rt;
  rt.priority = 0;  // a bench tool: the normal scheduler unless canhil run is asked
  emulator::RealtimeDriver driver(session, rt);
  const Nanos start = driver.start_time();

  stop_on_signals();
  const can_nodes::NodeSet emulated = session.scenario().emulate.at(0);
  std::printf("canhil nodes: robot on %s: %s (EC %.1f ms, %u bit/s)%s; physics every %.0f ms. Ctrl-C stops.\n",
              iface->c_str(), can_nodes::describe(emulated).c_str(), ec_ms, options.ftt.bit_rate,
              emulated.is_all() ? "" : ", the others are real boards on the bus", to_ms(session.step_period()));
  std::fflush(stdout);

  const Nanos end = duration_s > 0 ? start + from_seconds(duration_s) : kNever;
  Nanos next_report = start + std::chrono::seconds(5);
  const can_nodes::RobotNodes& nodes = *session.rig(0).nodes;
  while (!g_stop && driver.clock().now() < end) {
    driver.run_until(std::min(end, driver.clock().now() + std::chrono::seconds(1)), g_stop);
    for (const auto& [r, state] : driver.bus_state_changes()) {
      std::printf("canhil nodes: %s is %s\n", iface->c_str(), can_nodes::state_name(state));
      std::fflush(stdout);
    }
    if (!quiet && driver.clock().now() >= next_report) {
      const kinematics::Pose pose = session.snapshot().robots.at(0);
      const can_nodes::Node& timed = nodes.emulates(can_nodes::NodeId::kMaster)
                                         ? nodes.node(can_nodes::NodeId::kMaster)
                                         : *session.rig(0).nodes->nodes().front();
      const std::uint64_t tms =
          nodes.emulates(can_nodes::NodeId::kMaster) ? timed.counters().sent : timed.counters().triggers;
      std::printf("canhil nodes: %.0f s, %llu TMs, robot at (%.2f, %.2f) m, %llu bad frames, %llu late steps\n",
                  to_seconds(driver.clock().now() - start), static_cast<unsigned long long>(tms), pose.x_m, pose.y_m,
                  static_cast<unsigned long long>(nodes.bad_frames()),
                  static_cast<unsigned long long>(driver.physics_stats().late_steps));
      std::fflush(stdout);
      next_report += std::chrono::seconds(5);
    }
  }
  driver.stop();

  const emulator::RealtimeStats st = driver.physics_stats();
  std::printf("\ncanhil nodes: summary after %.1f s on %s\n", to_seconds(driver.clock().now() - start), iface->c_str());
  std::printf("  %-12s %10s %10s %10s %12s %10s\n", "node", "sent", "received", "bad", "send failed", "dropped");
  for (std::size_t i = 0; i < can_nodes::kNodeCount; ++i) {
    if (!nodes.emulates(static_cast<can_nodes::NodeId>(i))) {
      std::printf("  %-12s %10s\n", can_nodes::kNodeNames[i], "(a real board)");
      continue;
    }
    const auto& c = nodes.node(static_cast<can_nodes::NodeId>(i)).counters();
    std::printf("  %-12s %10llu %10llu %10llu %12llu %10llu\n", can_nodes::kNodeNames[i],
                static_cast<unsigned long long>(c.sent), static_cast<unsigned long long>(c.received),
                static_cast<unsigned long long>(c.bad_frames()), static_cast<unsigned long long>(c.send_failed),
                static_cast<unsigned long long>(driver.socket(0, i).stats().rx_overflow));
  }
  const kinematics::Pose pose = session.world().robot(0).pose();
  std::printf("  physics: %llu steps, %llu late (worst %.2f ms), %llu skipped; robot at (%.3f, %.3f) m, %.1f deg\n",
              static_cast<unsigned long long>(st.physics_steps), static_cast<unsigned long long>(st.late_steps),
              to_ms(st.worst_lateness), static_cast<unsigned long long>(st.skipped_steps), pose.x_m, pose.y_m,
              pose.heading_rad * 180 / 3.14159265);
  return 0;
}

}  // namespace canhil::app
