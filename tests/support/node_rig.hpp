// tests/support/node_rig.hpp — one robot's emulated nodes on a memory bus in
// virtual time, with a fake robot behind them and a test endpoint playing the
// laptop: what the node, schedule and timing tests drive. No physics.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/robot_nodes.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "support/fake_robot.hpp"
#include "support/laptop_endpoint.hpp"
#include "support/test_paths.hpp"

namespace canhil::test {

struct NodeRig {
  /// `emulate`: the nodes of the set (the others are for the test to play).
  explicit NodeRig(can_nodes::NodeSet emulate = can_nodes::NodeSet::all())
      : set(frames::MessageSet::load(shipped_dbc())),
        bus(clock),
        nodes(
            set, params, robot,
            [this](const std::string& name) {
              endpoints_asked.push_back(name);
              return std::unique_ptr<can_nodes::Endpoint>(bus.attach(name));
            },
            Nanos{0}, emulate),
        laptop(bus, set, params.ftt.elementary_cycle),
        run(clock) {
    for (can_nodes::Node* n : nodes.nodes()) run.add(*n);
    run.add(laptop);
  }
  NodeRig(const NodeRig&) = delete;
  NodeRig& operator=(const NodeRig&) = delete;

  std::shared_ptr<const frames::MessageSet> set;
  can_nodes::NodeParams params;
  FakeRobot robot;
  can_nodes::SimulatedClock clock;
  can_nodes::MemoryBus bus;
  std::vector<std::string> endpoints_asked;  ///< the names the node set asked endpoints for, in order
  can_nodes::RobotNodes nodes;
  LaptopEndpoint laptop;
  can_nodes::VirtualTime run;
};

}  // namespace canhil::test
