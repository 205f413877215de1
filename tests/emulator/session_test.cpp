// A session's one narrow surface, driven in virtual time: a consistent
// snapshot to read, and changes (a robot, the ball or an obstacle moved, a
// fault injected) that take effect at the next step, checked when asked; and
// what a team's agent is told of a robot canhil moved (COACH_INFO's
// relocations).
#include "canhil/emulator/session.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <thread>

#include "canhil/emulator/laptop_link.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "support/counter_watch.hpp"
#include "support/team_rtdb.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class SessionTest : public test::WatchedTest {
 protected:
  SessionTest() {
    static int counter = 0;
    setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 12) + (++counter << 6)).c_str(), 1);
    scenario_.world.robots = {physics::Placement{-3.0, 0.0, -90}, physics::Placement{3.0, 2.0, 90}};
    scenario_.world.obstacles = {physics::ObstaclePlacement{{0, -3, 0}, {}}};
    scenario_.world.ball_start = {-1.0, 1.0, scenario_.world.ball.radius_m};
    options_.messages = frames::MessageSet::load(test::shipped_dbc());
  }
  Scenario scenario_;
  SessionOptions options_;
};

TEST_F(SessionTest, TheSnapshotIsTheWorldAsTheLastStepLeftIt) {
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  const WorldSnapshot before = session.snapshot();
  EXPECT_EQ(before.steps, 0u);
  ASSERT_EQ(before.robots.size(), 2u);
  ASSERT_EQ(before.obstacles.size(), 1u);
  EXPECT_NEAR(before.robots[1].x_m, 3.0, 1e-9);
  driver.run_for(1s);
  const WorldSnapshot s = session.snapshot();
  EXPECT_EQ(s.steps, 100u);
  EXPECT_NEAR(s.time_s, 1.0, 1e-9);
  EXPECT_EQ(s.ball, session.world().ball_position());
  for (std::size_t r = 0; r < 2; ++r) {
    EXPECT_DOUBLE_EQ(s.robots[r].x_m, session.world().robot(r).pose().x_m);
  }
}

TEST_F(SessionTest, MovesTakeEffectAtTheNextStepNotBefore) {
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  driver.run_for(500ms);
  const double x_before = session.world().robot(1).pose().x_m;
  session.apply(MoveRobot{1, physics::Placement{5.0, -4.0, 30}});
  session.apply(MoveBall{{2.0, 2.0, 0.11}, {1.0, 0.0, 0.0}});
  session.apply(MoveObstacle{0, 4.0, 4.0});
  EXPECT_EQ(session.world().robot(1).pose().x_m, x_before) << "nothing moved yet";
  EXPECT_EQ(session.snapshot().robots[1].x_m, x_before);
  driver.run_for(10ms);  // one step
  const WorldSnapshot s = session.snapshot();
  EXPECT_NEAR(s.robots[1].x_m, 5.0, 0.01);
  EXPECT_NEAR(s.robots[1].y_m, -4.0, 0.01);
  EXPECT_NEAR(s.ball.x(), 2.01, 0.005) << "placed, then one step at 1 m/s";
  EXPECT_NEAR(s.obstacles[0].x(), 4.0, 1e-9);
  EXPECT_NEAR(s.obstacles[0].y(), 4.0, 1e-9);
  driver.run_for(1s);
  EXPECT_GT(session.world().ball_position().x(), 2.3) << "the ball rolls on with its new velocity";
}

TEST_F(SessionTest, AMistakenChangeIsRefusedAtOnceAndChangesNothing) {
  scenario_.bus.bit_rate = 0;  // an instant bus refuses a wire fault
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  EXPECT_THROW(session.apply(MoveRobot{2, {}}), SetupError);
  EXPECT_THROW(session.apply(MoveObstacle{1, 0, 0}), SetupError);
  EXPECT_THROW(session.apply(InjectFault{can_nodes::parse_fault("drop:Motor9")}), SetupError);
  session.refuse_error_frames("a CAN adapter");
  try {
    session.apply(InjectFault{can_nodes::parse_fault("error:M3_1")});
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("a CAN adapter"), std::string::npos) << e.what();
  }
  try {
    session.apply(InjectFault{can_nodes::parse_fault("busoff:laptop")});
    FAIL() << "a wire fault on an instant bus";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("give it a bit rate"), std::string::npos) << e.what();
  }
  driver.run_for(100ms);
  EXPECT_TRUE(session.fault_counts().empty());
}

TEST_F(SessionTest, AWireFaultInjectedDuringARunOnTheWireReachesTheWire) {
  scenario_.bus.bit_rate = 1'000'000;
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  driver.run_for(100ms);
  session.apply(InjectFault{can_nodes::parse_fault("busoff:Motor1")});
  driver.run_for(100ms);
  const wire::WireBus& wire = *driver.bus(0).wire_bus();
  std::uint64_t bus_offs = 0;
  for (wire::ControllerId c = 0; c < wire.controllers(); ++c) {
    if (wire.status(c).name == "Motor1") bus_offs = wire.status(c).bus_offs;
  }
  EXPECT_EQ(bus_offs, 1u);
}

TEST_F(SessionTest, AFaultInjectedDuringTheRunActsFromThenOn) {
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  counters.watch_nodes(*session.rig(0).nodes, "robot0.");
  driver.run_for(1s);
  session.apply(InjectFault{can_nodes::parse_fault("silence:Compass:0")});
  driver.run_for(1s);
  const auto counts = session.fault_counts();
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].applied, counts[0].matched) << "silence drops every frame from then on";
  EXPECT_EQ(counts[0].applied, 2u * 19u) << "both robots' compasses: the M8s after the next step (1.01 s) to 2 s";
  counters.expect("robot0.Compass.fault_dropped", 19);
  // In the trace: M8 until the step that applied the rule, none after.
  std::istringstream in(driver.trace());
  std::size_t before = 0, after = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.find(" vcan0 141#") == std::string::npos) continue;
    (line < "(1.010000)" ? before : after) += 1;
  }
  EXPECT_EQ(before, 21u) << "M8 every 50 ms up to 1.01 s";
  EXPECT_EQ(after, 0u);
  counters.finish();  // while the session's nodes exist
}

TEST_F(SessionTest, AnotherThreadMayReadAndChangeWhileTheRunGoesOn) {
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> looks{0};
  std::uint64_t seen = 0;
  std::uint64_t applied_at = ~std::uint64_t{0};
  std::thread viewer([&] {
    while (!done) {
      const WorldSnapshot s = session.snapshot();
      EXPECT_EQ(s.robots.size(), 2u);
      // One change per step seen: the changes waiting stay bounded, whatever the speeds.
      if (s.steps != applied_at) {
        session.apply(MoveBall{{0, 0, 0.11}, Eigen::Vector3d::Zero()});
        applied_at = s.steps;
      }
      seen = std::max(seen, s.steps);
      looks.fetch_add(1);
    }
  });
  // The run goes on in slices; after each, the viewer has looked at least once
  // more (on a loaded machine it may otherwise not be scheduled until the end).
  for (int slice = 0; slice < 20; ++slice) {
    const std::uint64_t before = looks.load();
    driver.run_for(100ms);
    while (looks.load() < before + 2) std::this_thread::yield();
  }
  done = true;
  viewer.join();
  EXPECT_GE(seen, 10u) << "the viewer saw the run between its slices";
  EXPECT_EQ(session.snapshot().steps, 200u);
}

TEST_F(SessionTest, TimedStepsCountEveryStepItsContactPointsAndTheVisionOnlyWhenAsked) {
  {
    Session session(plan_run(scenario_, options_));
    VirtualDriver driver(session);
    driver.run_for(200ms);
    EXPECT_EQ(session.step_timing().physics.steps, 0U) << "not asked: nothing timed";
    EXPECT_EQ(session.step_timing().physics.cpu, Nanos{0});
    EXPECT_EQ(session.step_timing().vision, Nanos{0});
  }
  options_.time_steps = true;
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session);
  driver.run_for(200ms);
  const PhysicsTiming& t = session.step_timing().physics;
  EXPECT_EQ(t.steps, session.snapshot().steps);
  EXPECT_GT(t.cpu, Nanos{0});
  // Each of the two robots stands on its three wheels in every substep.
  const auto substeps = static_cast<double>(scenario_.world.simulation.substeps);
  EXPECT_GE(t.contacts_per_step(), 2 * 3 * substeps);
  EXPECT_EQ(t.sum_x, static_cast<double>(session.world().contact_points()))
      << "the steps' contact points are all the world's";
  EXPECT_GT(session.step_timing().vision, Nanos{0}) << "two robots' camera frames in 200 ms";
}

TEST_F(SessionTest, TimedStepsWithoutVisionCountNoVision) {
  options_.time_steps = true;
  options_.vision_on = false;
  Session session(plan_run(scenario_, options_));
  VirtualOptions no_laptop;
  no_laptop.reference_handler_and_agent = false;
  VirtualDriver driver(session, no_laptop);
  driver.run_for(200ms);
  EXPECT_EQ(session.step_timing().physics.steps, session.snapshot().steps);
  EXPECT_EQ(session.step_timing().vision, Nanos{0});
}

// A team's own agent is told when canhil moved its robot: COACH_INFO's
// relocations, in CAMBADA's layout the robot's changePositionSN, on which
// CAMBADA's agent relocalises from scratch. Read back through the team's RTDB
// library (the stand-in, a CAMBADA-like table), as the agent reads it.
class RelocationTest : public test::WatchedTest {
 protected:
  RelocationTest() {
    const std::string team = test::source_dir() + "/tests/support/cambada_like/";
    scenario_.world.robots = {physics::Placement{-3.0, 0.0, -90}, physics::Placement{3.0, 2.0, 90}};
    scenario_.referee.enabled = true;
    scenario_.referee.restart_pause_s = 0.5;
    scenario_.laptop.rtdb_lib = test::team_rtdb_library();
    scenario_.laptop.rtdb_items = team + "rtdb_user.h";
    scenario_.laptop.rtdb_ini = team + "config/rtdb.ini";
    scenario_.laptop.layout = "cambada";
    options_.messages = frames::MessageSet::load(test::shipped_dbc());
    no_laptop_.reference_handler_and_agent = false;  // canhil's agent wants CMD_SETPOSE, which CAMBADA has not
  }
  // changePositionSN[agent - 1] of the base station's COACH_INFO in the
  // agent's database (CAMBADA's CoachInfo: six ints from byte 192).
  static std::int32_t serial(Session& session, int agent) {
    rtdb::Database& db = session.laptop()->database();
    std::vector<std::byte> coach(260);
    EXPECT_TRUE(db.get(agent, 0, *db.items().id("COACH_INFO"), coach));
    std::int32_t v = 0;
    std::memcpy(&v, coach.data() + 192 + 4 * (agent - 1), sizeof v);
    return v;
  }
  // Steps until the referee calls; the call's time.
  static Nanos run_to_a_call(Session& session, VirtualDriver& driver) {
    std::optional<Nanos> called;
    session.on_referee_call([&](const RefereeCall& c) { called = c.time; });
    for (int step = 0; step < 200 && !called; ++step) driver.run_for(session.step_period());
    session.on_referee_call(nullptr);
    EXPECT_TRUE(called.has_value()) << "no call within 2 s";
    return called.value_or(Nanos{0});
  }
  // A goal in the +x goal: a kick-off, both robots carried to their places.
  void score(Session& session) const {
    session.apply(MoveBall{{scenario_.world.field.length_m / 2 - 0.3, 0.0, 0.11}, {3.0, 0.0, 0.0}});
  }
  test::RtdbKeys keys_;
  Scenario scenario_;
  SessionOptions options_;
  VirtualOptions no_laptop_;
};

TEST_F(RelocationTest, EachCarryChangesTheRobotsSerialOnceTheDelayAfterIt) {
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session, no_laptop_);
  const Nanos delay = from_seconds(kRelocationDelayS);
  const Nanos step = session.step_period();
  ASSERT_EQ(delay % step, Nanos{0}) << "the delay ends on a step";
  driver.run_for(300ms);
  EXPECT_EQ(serial(session, 1), 0);
  EXPECT_EQ(serial(session, 2), 0);
  score(session);
  const Nanos carried = run_to_a_call(session, driver);
  ASSERT_EQ(session.referee()->calls().size(), 1u);
  ASSERT_EQ(session.referee()->calls()[0].restart, Restart::kKickoff);
  ASSERT_EQ(session.referee_placements(0), 1u);
  ASSERT_EQ(session.referee_placements(1), 1u);
  // Not in the carry's cycle, nor before the delay: what the agent would see is from before.
  driver.run_until(carried + delay - step);
  EXPECT_EQ(serial(session, 1), 0) << "one step before the delay";
  EXPECT_EQ(serial(session, 2), 0);
  EXPECT_EQ(session.coach().players[0].relocations, 0u);
  driver.run_until(carried + delay);
  EXPECT_EQ(serial(session, 1), 1) << "at the delay";
  EXPECT_EQ(serial(session, 2), 1);
  EXPECT_EQ(session.coach().players[1].relocations, 1u);
  EXPECT_EQ(session.snapshot().coach.players[0].relocations, 1u);
  driver.run_for(600ms);  // past the restart's pause, the coach written again and again
  EXPECT_EQ(serial(session, 1), 1) << "once per carry";
  EXPECT_EQ(serial(session, 2), 1);
  // A second carry: the second change, again the delay after it.
  score(session);
  const Nanos again = run_to_a_call(session, driver);
  ASSERT_EQ(session.referee_placements(0), 2u);
  driver.run_until(again + delay - step);
  EXPECT_EQ(serial(session, 1), 1);
  driver.run_until(again + delay);
  EXPECT_EQ(serial(session, 1), 2);
  EXPECT_EQ(serial(session, 2), 2);
  driver.run_for(300ms);
  EXPECT_EQ(serial(session, 1), 2);
}

TEST_F(RelocationTest, ARobotMovedFromOutsideChangesOnlyItsSerialTheDelayAfterTheStepThatMovedIt) {
  scenario_.referee.enabled = false;
  scenario_.laptop.relocation_delay_s = 0.2;  // the scenario's own delay
  Session session(plan_run(scenario_, options_));
  VirtualDriver driver(session, no_laptop_);
  const Nanos step = session.step_period();
  driver.run_for(200ms);
  session.apply(MoveRobot{1, physics::Placement{5.0, -4.0, 30}});  // the viewer's drag, a control command
  const Nanos moved = driver.now() + step;                         // at the next step
  driver.run_until(moved + 200ms - step);
  EXPECT_EQ(serial(session, 2), 0);
  driver.run_until(moved + 200ms);
  EXPECT_EQ(serial(session, 2), 1) << "the scenario's relocation_delay_s after the move";
  EXPECT_EQ(serial(session, 1), 0) << "the robot that stayed is not told";
  driver.run_for(500ms);
  EXPECT_EQ(serial(session, 2), 1);
}

}  // namespace
}  // namespace canhil::emulator
