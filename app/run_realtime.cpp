#include "run_realtime.hpp"

#include "canhil/emulator/laptop_link.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "stop_signals.hpp"

#include <atomic>

namespace canhil::app {
namespace {

void print_summary(FILE* out, const emulator::Session& session, const emulator::RealtimeDriver& driver, Nanos now) {
  const emulator::RealtimeStats st = driver.physics_stats();
  const physics::World& world = session.world();
  const Eigen::Vector3d b = world.ball_position();
  std::fprintf(out,
               "canhil run: %s after %.2f s; physics steps %llu, late %llu, skipped %llu, worst lateness %.1f ms\n",
               g_stop ? "stopped" : "done", to_seconds(now - driver.start_time()),
               static_cast<unsigned long long>(st.physics_steps), static_cast<unsigned long long>(st.late_steps),
               static_cast<unsigned long long>(st.skipped_steps), to_ms(st.worst_lateness));
  std::fprintf(out, "  ball at (%.2f, %.2f); %zu goal(s)\n", b.x(), b.y(), session.goals().size());
  for (std::size_t r = 0; r < session.robot_count(); ++r) {
    const emulator::Rig& rig = session.rig(r);
    const kinematics::Pose p = world.robot(r).pose();
    // TMs canhil's master sent, or, with a real master, those canhil's first node answered.
    const bool master = rig.nodes->emulates(can_nodes::NodeId::kMaster);
    const can_nodes::NodeCounters& tm =
        master ? rig.nodes->node(can_nodes::NodeId::kMaster).counters() : rig.nodes->nodes().front()->counters();
    std::fprintf(
        out, "  %s agent %d: at (%.2f, %.2f), %llu TMs %s, %llu bad frames, 24 V pack %.1f V (%.0f %%)\n",
        rig.interface.c_str(), rig.agent, p.x_m, p.y_m, static_cast<unsigned long long>(master ? tm.sent : tm.triggers),
        master ? "sent" : "heard from the real master", static_cast<unsigned long long>(rig.nodes->bad_frames()),
        world.robot(r).battery().power24_v, 100 * world.robot(r).charge()[2]);
    std::fprintf(out, "    bus: %s\n", can_nodes::describe(rig.nodes->bus_report()).c_str());
    for (const auto& c : rig.faults->counts()) {
      std::fprintf(out, "    fault %-24s %s\n", c.rule.c_str(), can_nodes::describe(c).c_str());
    }
  }
  if (const emulator::LaptopLink* laptop = session.laptop()) std::fputs(laptop->summary().c_str(), out);
  std::fputs(world.solver_health().describe("  ").c_str(), out);
}

}  // namespace

void say_the_wire(std::FILE* out, const emulator::Session& session, bool timed, const char* clock) {
  const emulator::BusPhysics& bus = session.options().bus;
  if (timed) {
    std::fprintf(out, "  %s, the user-space bus's broker on %s (docs/wire.md)\n", emulator::describe_bus(bus).c_str(),
                 clock);
    return;
  }
  if (!bus.timed()) {
    std::fprintf(out, "  %s\n", emulator::describe_bus(bus).c_str());
    return;
  }
  std::fprintf(out,
               "  %g kbit/s (%s): these buses (%s) deliver every frame at once, with no wire time, arbitration or "
               "errors; the bit rate times the FTT schedule only (canhil's timed wire runs with --virtual-time and "
               "on canhil's user-space bus: docs/wire.md)\n",
               bus.bit_rate / 1e3, bus.source(), can_nodes::bus_of(session.rig(0).interface));
}

int run_realtime(emulator::Session& session, const emulator::RealtimeOptions& options, const RealtimeOutput& output) {
  FILE* out = output.out;
  emulator::RealtimeDriver driver(session, options);
  const Nanos start = driver.start_time();
  stop_on_signals();
  char length[32] = "until Ctrl-C";
  if (output.length.seconds > 0) std::snprintf(length, sizeof length, "%g s", output.length.seconds);
  const emulator::Scenario& sc = session.scenario();
  std::fprintf(out, "canhil run: %zu robot(s), real time, %s (%s), seed %llu, %zu fault rule(s)\n", sc.robot_count(),
               length, output.length.source.c_str(), static_cast<unsigned long long>(sc.seed), sc.faults.size());
  say_the_wire(out, session, session.robot_count() > 0 && driver.timed_wire(0), "the wall clock");
  for (std::size_t r = 0; r < session.robot_count(); ++r) {
    const emulator::Rig& rig = session.rig(r);
    std::fprintf(out, "  robot %zu on %s (%s) for agent %d (start your handler and agent with AGENT=%d)\n", r,
                 rig.interface.c_str(), can_nodes::bus_of(rig.interface), rig.agent, rig.agent);
    if (const can_nodes::NodeSet e = sc.emulate.at(r); !e.is_all()) {
      std::fprintf(out, "    canhil emulates %s; the other nodes are real boards on %s\n",
                   can_nodes::describe(e).c_str(), rig.interface.c_str());
    }
  }
  std::fflush(out);
  const Nanos end = output.length.seconds > 0 ? start + from_seconds(output.length.seconds) : kNever;
  Nanos next_report = start + std::chrono::seconds(1);
  std::size_t goals_reported = 0;
  driver.start();
  bool priority_said = false;
  while (!g_stop && driver.clock().now() < end) {
    driver.run_until(std::min(end, driver.clock().now() + std::chrono::milliseconds(200)), g_stop);
    if (!priority_said && !driver.priority_problem().empty()) {
      std::fprintf(out, "canhil run: %s\n", driver.priority_problem().c_str());
      priority_said = true;
    }
    for (const auto& [r, state] : driver.bus_state_changes()) {
      std::fprintf(out, "canhil run: %s is %s\n", session.rig(r).interface.c_str(), can_nodes::state_name(state));
    }
    const emulator::WorldSnapshot s = session.snapshot();
    for (; goals_reported < s.goals.size(); ++goals_reported) {
      std::fprintf(out, "  GOAL at %.2f s\n", to_seconds(s.goals[goals_reported].time - start));
    }
    const Nanos now = driver.clock().now();
    if (!output.quiet && now >= next_report) {
      std::fprintf(out, "  t=%5.1f s  ball (%6.2f, %5.2f)", to_seconds(now - start), s.ball.x(), s.ball.y());
      for (std::size_t r = 0; r < session.robot_count(); ++r) {
        std::fprintf(out, "  %s (%5.2f, %5.2f)", session.rig(r).interface.c_str(), s.robots[r].x_m, s.robots[r].y_m);
      }
      std::fprintf(out, "  late steps %llu\n", static_cast<unsigned long long>(driver.physics_stats().late_steps));
      next_report += std::chrono::seconds(1);
    }
    std::fflush(out);
  }
  driver.stop();  // the world is this thread's again
  print_summary(out, session, driver, driver.clock().now());
  if (output.save_world) {
    physics::save_state(session.world().save(), *output.save_world);
    std::fprintf(out, "  world saved to %s (start a run from it with --restore-world)\n", output.save_world->c_str());
  }
  return g_stop ? 130 : 0;
}

}  // namespace canhil::app
