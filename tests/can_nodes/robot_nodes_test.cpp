// A robot's node set: one endpoint per node named from the one table plus the
// system monitor's watching endpoint, the names fault rules use, and the bus
// report over the whole set.
#include "canhil/can_nodes/robot_nodes.hpp"

#include <gtest/gtest.h>

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
  Lockstep& run_ = rig_.run;
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

}  // namespace
}  // namespace canhil::can_nodes
