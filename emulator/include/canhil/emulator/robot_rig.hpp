// canhil/emulator/robot_rig.hpp — one robot in virtual time, bare: a session
// of one robot (no vision, no RTDB, no reference laptop) driven in virtual
// time. Attach the laptop side to `bus()`, add() it and run: what a test of a
// handler, a node or the timing analysis, or a benchmark, needs. Not copyable.
#pragma once

#include <memory>
#include <utility>

#include "canhil/emulator/physics_robot_io.hpp"
#include "canhil/emulator/virtual_driver.hpp"

namespace canhil::emulator {

class RobotRig {
 public:
  /// The world's robots (one at kDefaultPlacement if it places none) get their
  /// node sets; the nodes start at time 0.
  RobotRig(std::shared_ptr<const frames::MessageSet> messages, physics::WorldParams world_params)
      : session_(scenario_of(std::move(world_params)), options_of(std::move(messages))),
        driver_(session_, VirtualOptions{false, false, false}) {}

  const std::shared_ptr<const frames::MessageSet>& messages() const { return session_.options().messages; }
  can_nodes::MemoryBus& bus() { return driver_.bus(0); }
  const can_nodes::Clock& clock() const { return driver_.clock(); }
  physics::World& world() { return session_.world(); }
  can_nodes::RobotNodes& nodes() { return *session_.rig(0).nodes; }
  const can_nodes::NodeParams& params() const { return session_.node_params(); }
  Session& session() { return session_; }

  /// A participant (the laptop side); must outlive the rig.
  void add(can_nodes::Participant& p) { driver_.add(p); }
  void run_until(Nanos end) { driver_.run_until(end); }
  void run_for(Nanos duration) { driver_.run_for(duration); }

 private:
  static Scenario scenario_of(physics::WorldParams world) {
    Scenario s;
    s.world = std::move(world);
    return s;
  }
  static SessionOptions options_of(std::shared_ptr<const frames::MessageSet> messages) {
    SessionOptions o;
    o.messages = std::move(messages);
    o.vision_on = false;
    return o;
  }

  Session session_;
  VirtualDriver driver_;
};

}  // namespace canhil::emulator
