// A robot's node set: one endpoint per node named from the one table plus the
// system monitor's watching endpoint, the names fault rules use, and the bus
// report over the whole set.
#include "canhil/can_nodes/robot_nodes.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <set>

#include "canhil/can_nodes/fault.hpp"
#include "support/counter_watch.hpp"
#include "support/node_rig.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

class RobotNodesTest : public test::WatchedTest {
 protected:
  RobotNodesTest() { counters.watch_nodes(nodes_); }
  test::NodeRig rig_;
  const std::shared_ptr<const frames::MessageSet>& set_ = rig_.set;
  RobotNodes& nodes_ = rig_.nodes;
  test::LaptopEndpoint& laptop_ = rig_.laptop;
  VirtualTime& run_ = rig_.run;
};

TEST_F(RobotNodesTest, OneEndpointPerNodeNamedFromTheTableAndOneToWatchTheBus) {
  std::vector<std::string> expected(kNodeNames.begin(), kNodeNames.end());
  expected.push_back("SysMon watch");
  EXPECT_EQ(rig_.endpoints_asked, expected);
  for (std::size_t i = 0; i < kNodeCount; ++i) {
    EXPECT_EQ(nodes_.node(static_cast<NodeId>(i)).name(), kNodeNames[i]);
  }
  EXPECT_STREQ(node_name(motor_node(2)), "Motor3");
  EXPECT_EQ(fault_node_name(node_name(NodeId::kMaster)), "FTT_master") << "rules write spaces as underscores";
}

TEST_F(RobotNodesTest, TheBusReportAddsUpTheWholeSet) {
  laptop_.m6_1 = frames::M6_1{0, 0.3};
  run_.run_until(1s - 1ns);  // ECs 0..99
  const BusReport r = nodes_.bus_report();
  EXPECT_EQ(r.tms_sent, 100u);
  EXPECT_EQ(r.ecs_skipped, 0u);
  EXPECT_EQ(r.fewest_triggers, 100u) << "every synchronous node handled every TM";
  EXPECT_EQ(r.monitor_triggers, 100u);
  std::uint64_t sent = 0;
  for (const Node* n : nodes_.nodes()) sent += n->counters().sent;
  EXPECT_EQ(r.sent, sent);
  // The monitor hears every frame on the bus: the nodes', its own and the laptop's.
  EXPECT_EQ(r.monitor_heard, sent + laptop_.sent_count());
  EXPECT_EQ(r.unknown_id + r.wrong_length + r.out_of_range, 0u);
  EXPECT_NE(describe(r).find("TMs: 100 sent, fewest handled 100"), std::string::npos) << describe(r);
}

TEST_F(RobotNodesTest, AFaultHookReachesEveryNode) {
  // Everything but the trigger messages dropped (without TMs no slave would speak).
  struct DropAllButTms final : FaultHook {
    std::uint32_t tm_id = 0;
    std::set<std::string> nodes;
    FaultDecision on_send(const std::string& node, const frames::CanFrame& f, Nanos) override {
      nodes.insert(node);
      FaultDecision d;
      d.drop = f.id != tm_id;
      return d;
    }
  } hook;
  hook.tm_id = set_->tm.message().id();
  nodes_.set_fault_hook(&hook);
  run_.run_until(1100ms);
  EXPECT_EQ(hook.nodes.size(), kNodeCount) << "every node's frames passed the hook";
  EXPECT_EQ(laptop_.frames().size(), laptop_.with_id(hook.tm_id).size()) << "only TMs reached the bus";
  for (const Node* n : nodes_.nodes()) {
    if (n == &nodes_.node(NodeId::kMaster)) continue;
    EXPECT_GT(n->counters().fault_dropped, 0u) << n->name();
    counters.allow(std::string(n->name()) + ".fault_dropped");
  }
}

// A bench: canhil emulates the motors, Pic_odom, the compass and the monitor;
// the FTT master and Pic_base are real boards (here a second set playing them).
TEST(RobotNodesSubset, NodesLeftToRealBoardsGetNoEndpointAndTheOthersFollowTheRealMastersTriggers) {
  NodeSet boards;
  for (const NodeId id : {NodeId::kMaster, NodeId::kPicBase}) boards.insert(id);
  NodeSet canhil;
  for (std::size_t i = 0; i < kNodeCount; ++i) {
    if (!boards.contains(static_cast<NodeId>(i))) canhil.insert(static_cast<NodeId>(i));
  }
  ASSERT_FALSE(canhil.is_all());
  test::NodeRig rig(canhil);
  EXPECT_EQ(rig.endpoints_asked,
            (std::vector<std::string>{"Motor1", "Motor2", "Motor3", "Pic_odom", "Compass", "SysMon", "SysMon watch"}));
  EXPECT_EQ(rig.nodes.nodes().size(), 6u);
  EXPECT_FALSE(rig.nodes.emulates(NodeId::kMaster));
  EXPECT_THROW(rig.nodes.node(NodeId::kPicBase), std::logic_error);
  EXPECT_EQ(describe(rig.nodes.emulated()), "Motor1, Motor2, Motor3, Pic_odom, Compass, SysMon");

  test::FakeRobot board_robot;  // what the real Pic_base drives (its kicker, grabber)
  RobotNodes real(
      rig.set, rig.params, board_robot,
      [&](const std::string& name) { return std::unique_ptr<Endpoint>(rig.bus.attach(name)); }, Nanos{0}, boards);
  for (Node* n : real.nodes()) rig.run.add(*n);
  rig.laptop.m6_1 = frames::M6_1{0, 0.5};  // forward
  rig.run.run_until(1s - 1ns);             // ECs 0..99 of the real master
  EXPECT_EQ(real.node(NodeId::kMaster).counters().sent, 100u);
  const BusReport r = rig.nodes.bus_report();
  EXPECT_EQ(r.tms_sent, 0u) << "canhil sent no TM";
  EXPECT_EQ(r.fewest_triggers, 100u) << "each of canhil's synchronous nodes answered every TM it heard";
  EXPECT_EQ(r.monitor_triggers, 100u);
  EXPECT_EQ(r.unknown_id + r.wrong_length + r.out_of_range, 0u);
  // The real Pic_base's set-points (M1) reached canhil's motor nodes, which drive the wheels.
  const auto& sp = real.pic_base().setpoints();
  EXPECT_NE(std::abs(sp[0]) + std::abs(sp[1]) + std::abs(sp[2]), 0);
  EXPECT_GT(std::abs(rig.robot.speed[0]) + std::abs(rig.robot.speed[1]) + std::abs(rig.robot.speed[2]), 1.0);
}

TEST(NodeNames, AConfigurationMayWriteANameInAnyCaseWithUnderscores) {
  EXPECT_EQ(node_by_name("FTT_master"), NodeId::kMaster);
  EXPECT_EQ(node_by_name("ftt master"), NodeId::kMaster);
  EXPECT_EQ(node_by_name("PIC_BASE"), NodeId::kPicBase);
  EXPECT_EQ(node_by_name("Motor3"), NodeId::kMotor3);
  EXPECT_EQ(node_by_name("Motor4"), std::nullopt);
  EXPECT_EQ(node_by_name(""), std::nullopt);
  EXPECT_EQ(node_name_list(), "FTT_master, Pic_base, Motor1, Motor2, Motor3, Pic_odom, Compass, SysMon");
  EXPECT_EQ(describe(NodeSet::all()), "all eight nodes");
  EXPECT_EQ(describe(NodeSet()), "no node");
}

}  // namespace
}  // namespace canhil::can_nodes
