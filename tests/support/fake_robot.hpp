// tests/support/fake_robot.hpp — a robot for the nodes without physics: it
// remembers what the nodes asked (wheel speeds, grabber, kicks) and answers
// what a test set (encoders, barrier). Encoders may follow the wheel speeds
// the nodes command (follow_wheels), so a closed loop through Pic_base, the
// motor nodes and Pic_odom runs without ODE.
#pragma once

#include <array>
#include <cmath>

#include "canhil/can_nodes/robot_io.hpp"
#include "canhil/kinematics/omni.hpp"

namespace canhil::test {

class FakeRobot final : public can_nodes::RobotIo {
 public:
  std::array<double, 3> speed{};  ///< rad/s the motor nodes last set
  std::array<std::int64_t, 3> encoder{};
  bool engaged = false;
  int kicks = 0;
  int grabber = -1;
  double heading_deg = 42.0;

  void set_wheel_speed(int w, double radps) override { speed[static_cast<std::size_t>(w)] = radps; }
  std::int64_t encoder_count(int w) const override { return encoder[static_cast<std::size_t>(w)]; }
  bool wheel_stalled(int) const override { return false; }
  bool over_current(int) const override { return false; }
  KickOutcome kick(bool, int power) override {
    if (power == 0) return KickOutcome::kNoPower;
    if (!engaged) return KickOutcome::kNotEngaged;
    ++kicks;
    return KickOutcome::kFired;
  }
  void set_grabber(int mode) override { grabber = mode; }
  bool ball_engaged() const override { return engaged; }
  double kicker_voltage_v() const override { return 180.0; }
  double compass_heading_deg() const override { return heading_deg; }
  BatteryVolts battery() const override { return {12.5, 12.4, 25.0}; }

  /// The wheels turn at the speeds the nodes set, for `dt_s`: the encoders move.
  void follow_wheels(double dt_s, const kinematics::EncoderSpec& spec = {}) {
    for (std::size_t w = 0; w < 3; ++w) {
      turned_rad_[w] += speed[w] * dt_s;
      encoder[w] = static_cast<std::int64_t>(std::floor(spec.counts(turned_rad_[w])));
    }
  }

 private:
  std::array<double, 3> turned_rad_{};
};

}  // namespace canhil::test
