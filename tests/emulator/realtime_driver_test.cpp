// The real-time driver in process, on a real vcan (the vcan suite): a session
// of one robot whose nodes answer a laptop played by the test, the physics on
// its own thread, and the narrow surface at work while it runs: a change to
// the world lands at a step, an injected fault on the nodes' next pass.
// Outcomes and counts, never timing: real time here may be an emulated machine.
#include "canhil/emulator/realtime_driver.hpp"

#include "canhil/can_nodes/medium.hpp"
#include "canhil/emulator/run_plan.hpp"

#include <gtest/gtest.h>

#include "support/counter_watch.hpp"
#include "support/driving_laptop.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

TEST(RealtimeDriver, RunsARobotOnVcanAndTakesChangesWhileItRuns) {
  const SessionOptions options = test::without_vision();
  Session session(plan_run(test::one_robot_on_vcan0(), options));
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
  watch.allow_suffix(".fault_dropped");  // the drop:M8 injected below
  const frames::MessageSet& set = *options.messages;

  // The laptop: M6 (forward, 0.5 m/s) in every slot that schedules it; counts M8.
  test::DrivingLaptop laptop("vcan0", set, set.m8.message().id());
  auto run_until = [&](auto done, Nanos limit) { return test::run_until(driver, done, limit); };
  driver.start();
  EXPECT_TRUE(run_until([&] { return laptop.tms() >= 50; }, 60s)) << "trigger messages flow";
  const double x0 = session.snapshot().robots[0].x_m;
  EXPECT_TRUE(run_until([&] { return session.snapshot().robots[0].x_m > x0 + 0.3; }, 60s))
      << "the laptop's M6 drove the robot forward (+x)";

  session.apply(MoveBall{{-1.0, -2.0, 0.11}, Eigen::Vector3d::Zero()});
  EXPECT_TRUE(run_until([&] { return session.snapshot().ball.y() < -1.9; }, 10s)) << "the ball was moved at a step";
  EXPECT_NEAR(session.snapshot().ball.x(), -1.0, 0.01);

  session.apply(InjectFault{can_nodes::parse_fault("drop:M8")});
  run_until([&] { return session.fault_counts().size() == 1 && session.fault_counts()[0].applied >= 10; }, 30s);
  const int m8_then = laptop.watched();
  run_until([] { return false; }, 1s);
  laptop.stop();
  driver.stop();
  EXPECT_LE(laptop.watched() - m8_then, 1) << "no M8 after the fault took effect (one may have been on its way)";
  const auto counts = session.fault_counts();
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].applied, counts[0].matched) << "every M8 since then dropped";
  EXPECT_EQ(session.rig(0).nodes->bad_frames(), 0u);
  EXPECT_GT(driver.physics_stats().physics_steps, 100u);
}

// --bit-rate in real time: on canhil's user-space bus its broker runs the
// wire (frames take their bits, each node a controller of its own), for the
// run only; the kernel's vcan keeps its own timing and says so.
TEST(RealtimeDriver, ATimedRunGivesTheUserSpaceBusItsWireForTheRunOnly) {
  SessionOptions options = test::without_vision();
  RunOverrides overrides;
  overrides.bit_rate = 1'000'000;
  Session session(plan_run(test::one_robot_on_vcan0(), options, overrides));
  ASSERT_TRUE(session.options().bus.timed());
  const bool user_space = can_nodes::SocketCanMedium("vcan0").kind() == can_nodes::MediumKind::kUserSpace;
  ASSERT_FALSE(can_nodes::SocketCanMedium("vcan0").counts().timed) << "an instant bus before the run";
  {
    RealtimeOptions rt;
    rt.priority = 0;
    RealtimeDriver driver(session, rt);
    EXPECT_EQ(driver.timed_wire(0), user_space);
    test::CounterWatch watch;
    const auto watched = watch.watch_session(session);
    for (const char* load : {".rx_overflow", ".send_dropped", ".send_failed"}) watch.allow_suffix(load);
    const frames::MessageSet& set = *options.messages;
    test::DrivingLaptop laptop("vcan0", set, set.m8.message().id());
    driver.start();
    EXPECT_TRUE(test::run_until(
        driver, [&] { return laptop.tms() >= 50 && laptop.watched() >= 20; }, 60s))
        << "trigger messages and the nodes' frames flow on the wire";
    laptop.stop();
    driver.stop();
    const can_nodes::MediumCounts counts = driver.medium(0).counts();
    EXPECT_EQ(counts.timed, user_space);
    if (user_space) {
      EXPECT_GT(counts.load, 0.0) << "the wire carried bits";
      EXPECT_EQ(counts.error_frames, 0U) << "every frame acknowledged, none in error";
    }
  }
  EXPECT_FALSE(can_nodes::SocketCanMedium("vcan0").counts().timed) << "instant again after the run";
}

}  // namespace
}  // namespace canhil::emulator
