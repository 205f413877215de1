// The real-time run's exchange between the node thread and the physics
// thread: nodes read what the last step published and their commands take
// effect at the next step; kicks are decided as the physics decides them.
// Silent trouble (test::WatchedTest): no node runs here (the nodes are built
// for their shared I/O only), so there is no counter of theirs to watch.
#include "canhil/emulator/shared_robot_io.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/emulator/physics_robot_io.hpp"
#include "canhil/emulator/realtime_physics.hpp"
#include "canhil/emulator/session.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

physics::WorldParams one_robot(double ball_x, double ball_y = 0.2) {
  physics::WorldParams p;
  p.robots = {physics::Placement{0, 0, 0}};  // front along world +y
  p.ball_start = {ball_x, ball_y, p.ball.radius_m};
  return p;
}

TEST(SharedRobotIo, NodesSeeTheLastPublishedStepAndCommandActAtTheNext) {
  physics::World world(one_robot(4));
  SharedRobotIo io(world.robot(0));
  const PhysicsRobotIo direct(world.robot(0));
  io.set_wheel_speed(0, 20.0);
  for (int k = 0; k < 20; ++k) world.step();  // not applied yet: the physics thread applies at its step
  EXPECT_LT(std::abs(world.robot(0).encoder_count(0)), 20) << "no command reached the world (it only settled)";
  EXPECT_EQ(io.encoder_count(0), 0);
  for (int k = 0; k < 20; ++k) {
    io.apply_commands();
    world.step();
  }
  EXPECT_GT(direct.encoder_count(0), 1000) << "the wheel turned";
  EXPECT_EQ(io.encoder_count(0), 0) << "nothing published yet";
  io.publish();
  EXPECT_EQ(io.encoder_count(0), direct.encoder_count(0));
  EXPECT_DOUBLE_EQ(io.compass_heading_deg(), direct.compass_heading_deg());
  EXPECT_DOUBLE_EQ(io.battery().power24_v, direct.battery().power24_v);
  EXPECT_EQ(io.ball_engaged(), direct.ball_engaged());
}

TEST(SharedRobotIo, KicksAreDecidedOnThePublishedStateAndFireAtTheNextStep) {
  physics::World far(one_robot(4));
  SharedRobotIo away(far.robot(0));
  EXPECT_EQ(away.kick(true, 0), KickOutcome::kNoPower);
  EXPECT_EQ(away.kick(true, 50), KickOutcome::kNotEngaged) << "the ball is 4 m away";
  // The ball in the mouth (grabber on), the capacitor charged: the kick fires at the next step.
  physics::World near(one_robot(0, 0.42));  // just in front of the mouth
  SharedRobotIo io(near.robot(0));
  io.set_grabber(100);
  for (int k = 0; k < 300 && !near.robot(0).ball_engaged(); ++k) {
    io.apply_commands();
    near.step();
  }
  ASSERT_TRUE(near.robot(0).ball_engaged()) << "the grabber pulled the ball in";
  io.publish();
  ASSERT_TRUE(io.ball_engaged());
  EXPECT_EQ(io.kick(true, 60), KickOutcome::kFired);
  EXPECT_LT(near.robot(0).last_kick_time_s(), 0) << "not fired before the physics step";
  io.apply_commands();
  near.step();
  EXPECT_GT(near.robot(0).last_kick_time_s(), 0) << "fired";
  for (int k = 0; k < 10; ++k) near.step();
  io.publish();
  EXPECT_LT(io.kicker_voltage_v(), near.robot(0).params().kicker.full_voltage_v) << "the capacitor gave its charge";
  EXPECT_EQ(io.kick(true, 60), KickOutcome::kNotEngaged) << "the ball has left";
}

TEST(RealtimePhysics, StepsTheSessionOnItsOwnThread) {
  Scenario scenario;
  scenario.world = one_robot(4);
  SessionOptions options;
  options.messages = frames::MessageSet::load(test::shipped_dbc());
  options.vision_on = false;
  Session session(plan_run(scenario, options));
  can_nodes::SimulatedClock unused;
  can_nodes::MemoryBus bus(unused);
  session.build_nodes(
      [&](std::size_t, const std::string& node) { return std::unique_ptr<can_nodes::Endpoint>(bus.attach(node)); },
      Session::IoMode::kShared, Nanos{0});
  SharedRobotIo& io = *session.rig(0).shared;
  const can_nodes::WallClock clock;
  RealtimePhysics physics(session, clock);
  io.set_wheel_speed(0, 20.0);
  io.set_wheel_speed(1, -20.0);
  physics.start(clock.now());
  // Counts, not rates: wait until some steps have run, however slowly.
  for (int k = 0; k < 500 && physics.stats().physics_steps < 20; ++k) std::this_thread::sleep_for(10ms);
  physics.stop();
  const RealtimeStats st = physics.stats();
  EXPECT_GE(st.physics_steps, 20u);
  EXPECT_NE(io.encoder_count(0), 0) << "commands applied and sensors published";
  const WorldSnapshot view = session.snapshot();
  EXPECT_EQ(view.steps, st.physics_steps) << "the session's after-step ran once a step";
  ASSERT_EQ(view.robots.size(), 1u);
  EXPECT_DOUBLE_EQ(view.robots[0].x_m, session.world().robot(0).pose().x_m) << "the snapshot is the last step's";
  EXPECT_DOUBLE_EQ(view.ball.x(), session.world().ball_position().x());
}

}  // namespace
}  // namespace canhil::emulator
