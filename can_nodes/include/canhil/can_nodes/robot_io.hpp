// canhil/can_nodes/robot_io.hpp — the narrow interface between the emulated
// microcontrollers and the robot they drive and sense.
//
// The nodes never see the physics engine: they set a wheel's speed, read its
// encoder, fire the kicker, read the barrier, set the grabber, read the heading
// and the battery. emulator/ implements this on the physics world; tests
// implement it with fakes. Called from the node loop's thread only.
#pragma once

#include <cstdint>

#include "canhil/base/robot.hpp"

namespace canhil::can_nodes {

class RobotIo {
 public:
  virtual ~RobotIo() = default;

  // Motor n (0..2): its controller's target speed, positive driving the base along F_n.
  virtual void set_wheel_speed(int wheel, double radps) = 0;
  /// Absolute encoder count of wheel n (the motor node reports it modulo 2^32).
  virtual std::int64_t encoder_count(int wheel) const = 0;
  virtual bool wheel_stalled(int wheel) const = 0;
  virtual bool over_current(int wheel) const = 0;

  // Kick system (Pic_base).
  virtual KickOutcome kick(bool low, int power) = 0;
  virtual void set_grabber(int mode) = 0;
  virtual bool ball_engaged() const = 0;
  virtual double kicker_voltage_v() const = 0;

  // Compass and battery.
  virtual double compass_heading_deg() const = 0;
  virtual BatteryVolts battery() const = 0;
};

}  // namespace canhil::can_nodes
