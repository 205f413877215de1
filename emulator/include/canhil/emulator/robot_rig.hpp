// canhil/emulator/robot_rig.hpp — one robot in virtual time: its world, its
// node set on a memory bus and a lockstep runner that ticks them. Attach the
// laptop side to `bus`, add it to `run` and run: what a test of a handler, a
// node or the timing analysis, or a benchmark, needs. Not copyable.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/emulator/lockstep.hpp"
#include "canhil/emulator/robot_nodes.hpp"

namespace canhil::emulator {

struct RobotRig {
  /// The world's first robot gets the node set; its nodes start at time 0.
  RobotRig(std::shared_ptr<const frames::MessageSet> messages, physics::WorldParams world_params)
      : set(std::move(messages)),
        world(std::move(world_params)),
        io(world.robot(0)),
        params(node_params_for(world.params().robot)),
        bus(clock),
        nodes(
            set, params, io, [this](const std::string& n) { return std::unique_ptr<can_nodes::Bus>(bus.attach(n)); },
            Nanos{0}),
        run(clock, &world) {
    for (can_nodes::Node* n : nodes.nodes()) run.add(*n);
  }

  std::shared_ptr<const frames::MessageSet> set;
  can_nodes::SimulatedClock clock;
  physics::World world;
  PhysicsRobotIo io;
  can_nodes::NodeParams params;
  can_nodes::MemoryBus bus;
  RobotNodes nodes;
  Lockstep run;
};

}  // namespace canhil::emulator
