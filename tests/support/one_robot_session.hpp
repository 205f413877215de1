// tests/support/one_robot_session.hpp — one robot in virtual time, bare: a
// session of one robot (no vision, no RTDB, no reference laptop) driven in
// virtual time. Attach the laptop side to `bus()`, add() it and run: what a
// test of a handler, a node or the timing analysis, or a benchmark, needs.
// Not copyable. Stands on emulator/ (a suite that includes it links
// canhil_emulator; bench/emulator_bench.cpp uses it too).
#pragma once

#include <memory>
#include <utility>

#include "canhil/emulator/physics_robot_io.hpp"
#include "canhil/emulator/virtual_driver.hpp"

namespace canhil::test {

class OneRobotSession {
 public:
  /// The world's robots (one at kDefaultPlacement if it places none) get their
  /// node sets; the nodes start at time 0.
  OneRobotSession(std::shared_ptr<const frames::MessageSet> messages, physics::WorldParams world_params)
      : session_(emulator::plan_run(scenario_of(std::move(world_params)), options_of(std::move(messages)))),
        driver_(session_, emulator::VirtualOptions{false, false, false}) {}

  const std::shared_ptr<const frames::MessageSet>& messages() const { return session_.options().messages; }
  can_nodes::MemoryBus& bus() { return driver_.bus(0); }
  const can_nodes::Clock& clock() const { return driver_.clock(); }
  physics::World& world() { return session_.world(); }
  can_nodes::RobotNodes& nodes() { return *session_.rig(0).nodes; }
  const can_nodes::NodeParams& params() const { return session_.node_params(); }
  emulator::Session& session() { return session_; }

  /// A participant (the laptop side); must outlive the session.
  void add(can_nodes::Participant& p) { driver_.add(p); }
  void run_until(Nanos end) { driver_.run_until(end); }
  void run_for(Nanos duration) { driver_.run_for(duration); }

 private:
  static emulator::Scenario scenario_of(physics::WorldParams world) {
    emulator::Scenario s;
    s.world = std::move(world);
    s.bus.bit_rate = 0;  // the instant bus: a test's endpoints send at will (a run's default is the DBC's Baudrate)
    return s;
  }
  static emulator::SessionOptions options_of(std::shared_ptr<const frames::MessageSet> messages) {
    emulator::SessionOptions o;
    o.messages = std::move(messages);
    o.vision_on = false;
    return o;
  }

  emulator::Session session_;
  emulator::VirtualDriver driver_;
};

}  // namespace canhil::test
