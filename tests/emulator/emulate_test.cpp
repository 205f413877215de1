// A bench that mixes real boards and emulated nodes (`emulate = [...]`): the
// scenario's lists and their mistakes, and a run in virtual time in which the
// test plays the real FTT master and Pic_base on the robot's bus while canhil
// emulates the rest: the reference laptop's loop closes through both.
#include <gtest/gtest.h>

#include <cmath>

#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/robot_nodes.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/scenario_writer.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/physics/config.hpp"
#include "support/counter_watch.hpp"
#include "support/error_of.hpp"
#include "support/fake_robot.hpp"
#include "support/rtdb_ipc.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;
using can_nodes::NodeId;
using can_nodes::NodeSet;

NodeSet set_of(std::initializer_list<NodeId> ids) {
  NodeSet s;
  for (const NodeId id : ids) s.insert(id);
  return s;
}

// Everything but the FTT master and Pic_base.
const char* const kBench = R"([run]
duration_s = 6
emulate = ["Motor1", "Motor2", "Motor3", "Pic_odom", "compass", "SYSMON"]
)";

std::string bench_error_of(const std::string& text) {
  return test::error_of<physics::ConfigError>([&] { parse_scenario(text, "bench.toml"); });
}

// Every test here fails on a node counter that moved unexpectedly.
class Emulate : public test::WatchedTest {};

TEST_F(Emulate, AScenarioListsTheNodesCanhilPlaysForEveryRobotOrPerRobot) {
  const NodeSet slaves =
      set_of({NodeId::kMotor1, NodeId::kMotor2, NodeId::kMotor3, NodeId::kPicOdom, NodeId::kCompass, NodeId::kSysMon});
  const Scenario one = parse_scenario(kBench, "bench.toml");
  ASSERT_EQ(one.emulate.size(), 1u);
  EXPECT_EQ(one.emulate[0], slaves);
  EXPECT_TRUE(one.mixes_real_boards());

  const std::string two_robots = "[[robots]]\nx_m = -1\n[[robots]]\nx_m = 1\n";
  const Scenario each =
      parse_scenario(two_robots + "[run]\nemulate = [[\"Motor1\"], [\"FTT_master\", \"Pic_base\"]]\n", "bench.toml");
  EXPECT_EQ(each.emulate,
            (std::vector<NodeSet>{set_of({NodeId::kMotor1}), set_of({NodeId::kMaster, NodeId::kPicBase})}));
  const Scenario plain = parse_scenario(two_robots, "bench.toml");
  EXPECT_EQ(plain.emulate, (std::vector<NodeSet>{NodeSet::all(), NodeSet::all()}));
  EXPECT_FALSE(plain.mixes_real_boards());

  // A team's robot gives its own; the others take [run]'s.
  const Scenario teams = parse_scenario(R"([run]
emulate = ["Pic_base", "Motor1", "Motor2", "Motor3", "Pic_odom", "Compass", "SysMon"]
[[teams]]
name = "a"
[[teams.robots]]
x_m = -2
emulate = ["Motor1"]
[[teams.robots]]
x_m = -1
[[teams]]
name = "b"
[[teams.robots]]
x_m = 2
)",
                                        "bench.toml");
  ASSERT_EQ(teams.emulate.size(), 3u);
  EXPECT_EQ(teams.emulate[0], set_of({NodeId::kMotor1}));
  EXPECT_FALSE(teams.emulate[1].contains(NodeId::kMaster));
  EXPECT_TRUE(teams.emulate[1].contains(NodeId::kPicBase));
  EXPECT_EQ(teams.emulate[2], teams.emulate[1]);

  // Saved and read again, a run keeps which boards are real.
  Session session(plan_run(one, [] {
    SessionOptions o;
    o.messages = frames::MessageSet::load(test::shipped_dbc());
    o.vision_on = false;
    return o;
  }()));
  EXPECT_EQ(parse_scenario(scenario_toml(one, session.snapshot()), "saved.toml").emulate, one.emulate);
}

TEST_F(Emulate, MistakesInTheListsAreNamedWithTheirLine) {
  EXPECT_NE(bench_error_of("[run]\nemulate = [\"Motor4\"]\n")
                .find("bench.toml:2: run.emulate: not a node's name; the nodes "
                      "are FTT_master, Pic_base"),
            std::string::npos)
      << bench_error_of("[run]\nemulate = [\"Motor4\"]\n");
  EXPECT_NE(bench_error_of("[run]\nemulate = [\"Motor1\", \"motor1\"]\n").find("motor1 appears twice"),
            std::string::npos);
  EXPECT_NE(bench_error_of("[run]\nemulate = []\n").find("run.emulate: must list the nodes canhil emulates"),
            std::string::npos);
  EXPECT_NE(bench_error_of("[run]\nemulate = \"Motor1\"\n").find("run.emulate: must be a list"), std::string::npos);
  EXPECT_NE(bench_error_of("[run]\nemulate = [[\"Motor1\"], [\"Motor2\"]]\n").find("give one list per robot"),
            std::string::npos);
  EXPECT_NE(bench_error_of("[[teams]]\n[[teams.robots]]\nemulate = [\"Pic_bse\"]\n")
                .find("bench.toml:3: teams.robots.emulate"),
            std::string::npos)
      << bench_error_of("[[teams]]\n[[teams.robots]]\nemulate = [\"Pic_bse\"]\n");
  Scenario none;
  none.emulate = {NodeSet()};
  EXPECT_NE(test::error_of([&] { complete(none); }).find("robot 1 emulates no node"), std::string::npos);
}

TEST_F(Emulate, CanhilsNodesFollowARealMasterAndARealPicBaseClosesTheLoop) {
  test::RtdbKeys keys;
  const Scenario s = parse_scenario(kBench, "bench.toml");
  SessionOptions o;
  o.messages = frames::MessageSet::load(test::shipped_dbc());
  Session refused(plan_run(s, o));
  EXPECT_NE(test::error_of([&] { VirtualDriver d(refused, {}); }).find("run that scenario in real time"),
            std::string::npos)
      << "without someone to play the real boards, virtual time refuses the scenario";

  Session session(plan_run(s, o));
  VirtualOptions v;
  v.caller_plays_real_boards = true;
  v.check_timing = true;
  VirtualDriver driver(session, v);
  // The real boards: the FTT master and Pic_base (its kicker and grabber its own).
  test::FakeRobot board_robot;
  can_nodes::RobotNodes boards(
      o.messages, session.node_params(), board_robot,
      [&](const std::string& name) { return std::unique_ptr<can_nodes::Endpoint>(driver.bus(0).attach(name)); },
      Nanos{0}, set_of({NodeId::kMaster, NodeId::kPicBase}));
  for (can_nodes::Node* n : boards.nodes()) driver.add(*n);
  const auto watching = counters.watch_session(session);

  const physics::Placement start = s.world.robots[0];
  driver.run_for(6s - 1ns);  // ECs 0..599
  const can_nodes::RobotNodes& canhil = *session.rig(0).nodes;
  const can_nodes::BusReport report = canhil.bus_report();
  const std::uint64_t tms = boards.node(NodeId::kMaster).counters().sent;
  EXPECT_EQ(tms, 600u);
  EXPECT_EQ(report.tms_sent, 0u);
  EXPECT_GE(report.fewest_triggers + 1, tms) << "canhil's nodes answered the real master's TMs";
  EXPECT_EQ(canhil.bad_frames() + boards.bad_frames(), 0u);
  EXPECT_EQ(driver.ftt_violations(0), 0u) << "the mixed bus keeps FTT-CAN's windows and periods";
  const kinematics::Pose at = session.world().robot(0).pose();
  EXPECT_GT(std::hypot(at.x_m - start.x_m, at.y_m - start.y_m), 0.5)
      << "the agent's M6 went through the real Pic_base to canhil's motor nodes and moved the robot";
}

}  // namespace
}  // namespace canhil::emulator
