// A bench on vcan (the vcan suite): canhil emulates the motor nodes,
// Pic_odom, the compass and the system monitor in real time, and the test
// plays the real boards — the FTT master and Pic_base, on sockets of their own
// and a thread of their own — plus the laptop. canhil's nodes follow the real
// master's trigger messages, and the laptop's M6 reaches canhil's motors
// through the real Pic_base. Outcomes and counts, never timing.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "canhil/can_nodes/realtime.hpp"
#include "canhil/can_nodes/robot_nodes.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/realtime_driver.hpp"
#include "canhil/emulator/wall_waiter.hpp"
#include "support/counter_watch.hpp"
#include "support/driving_laptop.hpp"
#include "support/fake_robot.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;
using can_nodes::NodeId;

TEST(VcanEmulate, CanhilsNodesFollowARealMasterAndARealPicBaseDrivesThem) {
  can_nodes::NodeSet boards;
  boards.insert(NodeId::kMaster);
  boards.insert(NodeId::kPicBase);
  can_nodes::NodeSet canhil;
  for (std::size_t i = 0; i < can_nodes::kNodeCount; ++i) {
    if (!boards.contains(static_cast<NodeId>(i))) canhil.insert(static_cast<NodeId>(i));
  }
  Scenario scenario = test::one_robot_on_vcan0();
  scenario.emulate = {canhil};
  const SessionOptions options = test::without_vision();
  Session session(plan_run(scenario, options));
  RealtimeOptions rt;
  rt.priority = 0;
  RealtimeDriver driver(session, rt);
  // Silent trouble in canhil's nodes fails the test: a frame of a wrong length
  // or out of range, an unknown id, an error frame. A full queue or a send the
  // kernel refused is the machine's in real time (a busy one fills queues),
  // not canhil's: allowed.
  test::CounterWatch watch;
  const auto watched = watch.watch_session(session);
  for (const char* load : {".rx_overflow", ".send_dropped", ".send_failed"}) watch.allow_suffix(load);
  const frames::MessageSet& set = *options.messages;
  EXPECT_THROW(driver.socket(0, static_cast<std::size_t>(NodeId::kMaster)), std::out_of_range)
      << "canhil opened no socket for a real board";

  // The real boards, on their own sockets and thread (SocketCAN's loopback lets each socket hear the others).
  test::FakeRobot board_robot;
  std::vector<int> board_fds;
  can_nodes::WallClock wall;
  const Nanos ec = options.ftt.elementary_cycle;
  can_nodes::RobotNodes real(
      options.messages, session.node_params(), board_robot,
      [&](const std::string&) {
        auto bus = can_nodes::SocketCanBus::open("vcan0");
        board_fds.push_back(bus->fd());
        return std::unique_ptr<can_nodes::Endpoint>(std::move(bus));
      },
      (wall.now() / ec + 5) * ec, boards);
  WallWaiter board_waiter(board_fds);
  can_nodes::Realtime board_loop(wall, [&](Nanos d) { board_waiter.wait(d); });
  for (can_nodes::Node* n : real.nodes()) board_loop.add(*n);
  std::atomic<bool> stop{false};
  std::thread board_thread([&] { board_loop.run_until(kNever, stop); });

  // The laptop: M6 (forward, 0.5 m/s) in every slot that schedules it; counts the odometry (M4_1).
  test::DrivingLaptop laptop("vcan0", set, set.m4_1.message().id());
  auto run_until = [&](auto done, Nanos limit) { return test::run_until(driver, done, limit); };
  driver.start();
  const double x0 = session.snapshot().robots[0].x_m;
  EXPECT_TRUE(run_until([&] { return laptop.tms() >= 50 && laptop.watched() >= 20; }, 60s))
      << laptop.tms() << " TMs, " << laptop.watched() << " M4_1";
  EXPECT_TRUE(run_until([&] { return session.snapshot().robots[0].x_m > x0 + 0.2; }, 60s))
      << "the laptop's M6 went through the real Pic_base to canhil's motor nodes: the robot drove forward (+x)";
  stop = true;
  laptop.stop();
  board_thread.join();
  driver.stop();

  // Read once every thread has stopped.
  const can_nodes::RobotNodes& emulated = *session.rig(0).nodes;
  const can_nodes::BusReport report = emulated.bus_report();
  const std::uint64_t real_tms = real.node(NodeId::kMaster).counters().sent;
  EXPECT_EQ(report.tms_sent, 0u) << "canhil sent no trigger message";
  EXPECT_GT(real_tms, 50u);
  EXPECT_GT(report.fewest_triggers, real_tms / 2) << "canhil's synchronous nodes answered the real master's TMs";
  EXPECT_EQ(emulated.bad_frames(), 0u);
  EXPECT_EQ(real.bad_frames(), 0u);
}

}  // namespace
}  // namespace canhil::emulator
