// The whole robot in virtual time: a test endpoint plays the laptop on the
// memory bus; behind the nodes is the physics world.
#include <gtest/gtest.h>

#include "canhil/frames/candump.hpp"

#include "support/counter_watch.hpp"
#include "support/laptop_endpoint.hpp"
#include "support/one_robot_session.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

// A robot and a laptop endpoint; its nodes' error counters are watched and
// checked when it goes (a test says what it provokes).
struct RobotAndLaptop : test::OneRobotSession {
  explicit RobotAndLaptop(test::CounterWatch& watch, physics::WorldParams wp = default_world())
      : test::OneRobotSession(frames::MessageSet::load(test::shipped_dbc()), std::move(wp)),
        laptop(bus(), messages(), params().ftt.elementary_cycle),
        watch_(watch) {
    add(laptop);
    watch_.watch_nodes(nodes());
  }
  ~RobotAndLaptop() { watch_.finish(); }
  RobotAndLaptop(const RobotAndLaptop&) = delete;
  RobotAndLaptop& operator=(const RobotAndLaptop&) = delete;
  static physics::WorldParams default_world() {
    physics::WorldParams p;
    p.robots = {physics::Placement{0, 0, 0}};  // front along world +y
    p.ball_start = {4, 4, p.ball.radius_m};
    return p;
  }
  frames::M4_1 last_m4_1() const { return laptop.decoded(messages()->m4_1).back(); }
  frames::M4_2 last_m4_2() const { return laptop.decoded(messages()->m4_2).back(); }

  test::LaptopEndpoint laptop;
  test::CounterWatch& watch() { return watch_; }

 private:
  test::CounterWatch& watch_;
};

class ClosedLoop : public test::WatchedTest {};

TEST_F(ClosedLoop, DrivingForwardTwoSecondsMovesOdometryAboutOneMetre) {
  RobotAndLaptop r(counters);
  r.laptop.m6_1 = frames::M6_1{0, 0.5};
  r.run_until(2s);
  r.laptop.m6_1.reset();
  r.run_for(600ms);  // brakes, then the next M4
  const frames::M4_1 m4 = r.last_m4_1();
  EXPECT_NEAR(m4.y, 1.0, 0.1) << "forward is the robot's +y";
  EXPECT_NEAR(m4.x, 0.0, 0.02);
  EXPECT_NEAR(r.last_m4_2().theta, 0.0, 0.02);
  // Odometry agrees with where the robot really is.
  const kinematics::Pose truth = r.world().robot(0).pose();
  EXPECT_NEAR(m4.y, truth.y_m, 0.01);
  EXPECT_NEAR(m4.x, truth.x_m, 0.01);
}

TEST_F(ClosedLoop, M5ResetBringsOdometryToZeroAndM5SetsAPose) {
  RobotAndLaptop r(counters);
  r.laptop.m6_1 = frames::M6_1{0.3, 0.3};
  r.run_until(1s);
  r.laptop.m6_1.reset();
  r.run_for(500ms);
  ASSERT_GT(std::hypot(r.last_m4_1().x, r.last_m4_1().y), 0.2);
  r.laptop.send(r.messages()->m5_1.encode(frames::M5_1{0, 0}));
  r.laptop.send(r.messages()->m5_2.encode(frames::M5_2{0, frames::M5_2::kReset}));
  r.run_for(100ms);
  EXPECT_NEAR(r.last_m4_1().x, 0.0, 1e-4);
  EXPECT_NEAR(r.last_m4_1().y, 0.0, 1e-4);
  EXPECT_NEAR(r.last_m4_2().theta, 0.0, 1e-5);
  r.laptop.send(r.messages()->m5_1.encode(frames::M5_1{2.5, -1.25}));
  r.laptop.send(r.messages()->m5_2.encode(frames::M5_2{1.5, frames::M5_2::kSetPose}));
  r.run_for(100ms);
  EXPECT_NEAR(r.last_m4_1().x, 2.5, 1e-4);
  EXPECT_NEAR(r.last_m4_1().y, -1.25, 1e-4);
  EXPECT_NEAR(r.last_m4_2().theta, 1.5, 1e-5);
}

physics::WorldParams ball_in_front(double distance) {
  physics::WorldParams p = RobotAndLaptop::default_world();
  p.ball_start = {0, distance, p.ball.radius_m};
  return p;
}

TEST_F(ClosedLoop, M7KicksOnlyWhenTheBallIsEngaged) {
  {
    RobotAndLaptop r(counters, ball_in_front(1.5));  // out of reach
    r.run_until(100ms);
    frames::M7 m7;
    m7.kick = frames::M7::make_kick(true, 40);
    r.laptop.send(r.messages()->m7.encode(m7));
    r.run_for(500ms);
    EXPECT_LT(r.world().ball_velocity().norm(), 0.01) << "not engaged: nothing happens";
    EXPECT_EQ(r.laptop.decoded(r.messages()->m9).back().just_kicked, 0);
  }
  {
    const physics::RobotParams robot;
    RobotAndLaptop r(counters, ball_in_front(robot.body_radius_m - robot.mouth_depth_m + 0.11));
    frames::M7 grab;
    grab.grabber_mode = 100;
    r.laptop.send(r.messages()->m7.encode(grab));
    r.run_until(300ms);
    ASSERT_EQ(r.laptop.decoded(r.messages()->m9).back().ball_engaged, 1);
    frames::M7 m7;
    m7.kick = frames::M7::make_kick(true, 40);
    m7.grabber_mode = 100;
    r.laptop.send(r.messages()->m7.encode(m7));
    r.run_for(40ms);
    EXPECT_GT(r.world().ball_velocity().y(), 5.0) << "launched forward";
    const auto m9 = r.laptop.decoded(r.messages()->m9);
    EXPECT_EQ(m9.back().just_kicked, 1);
    EXPECT_LT(m9.back().kicker_voltage, 170.0) << "the capacitor discharged";
  }
}

TEST_F(ClosedLoop, SilenceOnM6BrakesWithinTheWatchdogTime) {
  RobotAndLaptop r(counters);
  r.laptop.m6_1 = frames::M6_1{0, 1.0};
  r.run_until(1s);
  ASSERT_GT(r.world().robot(0).twist().vy_mps, 0.9);
  r.laptop.m6_1.reset();
  r.run_for(r.params().watchdog + 30ms);  // the watchdog plus one M1 period
  const auto m1 = r.laptop.decoded(r.messages()->m1);
  EXPECT_EQ(m1.back().enable, 0);
  EXPECT_EQ(m1.back().setpoint_1, 0);
  r.run_for(400ms);
  EXPECT_LT(std::fabs(r.world().robot(0).twist().vy_mps), 0.01) << "stopped";
}

TEST_F(ClosedLoop, ABurstOfJunkIsCountedAndEveryNodeHandlesEveryTriggerMessage) {
  RobotAndLaptop r(counters);
  r.run_until(100ms);
  // 6 000 frames in one instant: more than the system monitor's queue holds (4 096).
  auto junk = r.bus().attach("junk");
  for (int k = 0; k < 6000; ++k) {
    frames::CanFrame f = frames::make_data_frame(static_cast<std::uint32_t>(0x7F0 + k % 8), {1, 2, 3});  // unknown ids
    if (k % 3 == 0) f = frames::make_data_frame(r.messages()->tm.message().id(), {9});  // a TM of the wrong length
    ASSERT_EQ(junk->send(f), can_nodes::SendStatus::kOk);
  }
  r.run_until(1s);
  // The 2 000 short TMs, counted by every node that takes TMs; of the 4 000
  // unknown ids, those that reached the monitor before its queue overflowed.
  for (const char* n : {"Pic_base", "Motor1", "Motor2", "Motor3", "Pic_odom", "Compass"}) {
    r.watch().expect(std::string(n) + ".wrong_length", 2000);
  }
  r.watch().allow("SysMon.unknown_id");
  const can_nodes::BusReport b = r.nodes().bus_report();
  EXPECT_EQ(b.monitor_heard + b.monitor_overflow, 6000 + b.sent)
      << "everything on the bus reached the monitor's watching endpoint or was counted lost";
  EXPECT_EQ(b.monitor_overflow, 6000u - 4096u);
  EXPECT_GE(b.tms_sent, 100u) << "one TM per 10 ms EC over 1 s";
  EXPECT_EQ(b.fewest_triggers, b.tms_sent) << b.fewest_node << " missed a TM: " << can_nodes::describe(b);
  EXPECT_EQ(b.monitor_triggers, b.tms_sent) << "the monitor too, though its watching queue overflowed";
  EXPECT_EQ(b.ecs_skipped, 0u);
  EXPECT_GE(b.wrong_length, 2000u) << "the short TMs, counted by the nodes that take TMs";
  EXPECT_EQ(can_nodes::describe(b).rfind("nodes sent ", 0), 0u);
}

TEST_F(ClosedLoop, VirtualTimeRunsAreDeterministic) {
  auto trace = [this] {
    RobotAndLaptop r(counters);
    r.laptop.m6_1 = frames::M6_1{0.2, 0.6};
    r.laptop.m6_2.va = 0.5;
    r.run_until(1500ms);
    std::string out;
    for (const auto& f : r.laptop.frames())
      out += std::to_string(f.time.count()) + frames::format_compact(f.frame) + "\n";
    return out;
  };
  const std::string a = trace();
  EXPECT_EQ(a, trace());
  EXPECT_GT(a.size(), 1000u);
}

}  // namespace
}  // namespace canhil::emulator
