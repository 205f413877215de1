// canhil/emulator/physics_robot_io.hpp — the nodes' RobotIo on a physics
// robot, for a node loop on the thread that steps the world (virtual time),
// and the node parameters that match a physical robot.
#pragma once

#include "canhil/can_nodes/nodes.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::emulator {

class PhysicsRobotIo final : public can_nodes::RobotIo {
 public:
  explicit PhysicsRobotIo(physics::Robot& robot) : robot_(robot) {}
  void set_wheel_speed(int wheel, double radps) override { robot_.set_wheel_speed(wheel, radps); }
  std::int64_t encoder_count(int wheel) const override { return robot_.encoder_count(wheel); }
  bool wheel_stalled(int wheel) const override { return robot_.wheel_stalled(wheel); }
  bool over_current(int wheel) const override { return robot_.over_current(wheel); }
  KickOutcome kick(bool low, int power) override { return robot_.kick(low, power).outcome; }
  void set_grabber(int mode) override { robot_.set_grabber(mode); }
  bool ball_engaged() const override { return robot_.ball_engaged(); }
  double kicker_voltage_v() const override { return robot_.kicker_voltage_v(); }
  double compass_heading_deg() const override { return robot_.compass_heading_deg(); }
  BatteryVolts battery() const override { return robot_.battery(); }

 private:
  physics::Robot& robot_;
};

/// Node parameters that match a physical robot (its wheels and encoders).
can_nodes::NodeParams node_params_for(const physics::RobotParams& robot, const frames::FttConfig& ftt = {});

}  // namespace canhil::emulator
