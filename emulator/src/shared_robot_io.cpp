#include "canhil/emulator/shared_robot_io.hpp"

#include <algorithm>

#include "canhil/emulator/physics_robot_io.hpp"

namespace canhil::emulator {

SharedRobotIo::SharedRobotIo(physics::Robot& robot) : robot_(robot), kicker_(robot.params().kicker) { publish(); }

void SharedRobotIo::set_wheel_speed(int wheel, double radps) {
  const std::lock_guard lock(mutex_);
  wheel_.at(static_cast<std::size_t>(wheel)) = radps;
}

std::int64_t SharedRobotIo::encoder_count(int wheel) const {
  const std::lock_guard lock(mutex_);
  return sensors_.encoder.at(static_cast<std::size_t>(wheel));
}

bool SharedRobotIo::wheel_stalled(int wheel) const {
  const std::lock_guard lock(mutex_);
  return sensors_.stalled.at(static_cast<std::size_t>(wheel));
}

bool SharedRobotIo::over_current(int wheel) const {
  const std::lock_guard lock(mutex_);
  return sensors_.over_current.at(static_cast<std::size_t>(wheel));
}

KickOutcome SharedRobotIo::kick(bool low, int power) {
  const std::lock_guard lock(mutex_);
  // The physics' own rule, on the state its last step published.
  const KickOutcome outcome = physics::kick_outcome(kicker_, power, sensors_.engaged, sensors_.kicker_v);
  if (outcome == KickOutcome::kFired) kicks_.emplace_back(low, power);
  return outcome;
}

void SharedRobotIo::set_grabber(int mode) {
  const std::lock_guard lock(mutex_);
  grabber_ = mode;
}

bool SharedRobotIo::ball_engaged() const {
  const std::lock_guard lock(mutex_);
  return sensors_.engaged;
}

double SharedRobotIo::kicker_voltage_v() const {
  const std::lock_guard lock(mutex_);
  return sensors_.kicker_v;
}

double SharedRobotIo::compass_heading_deg() const {
  const std::lock_guard lock(mutex_);
  return sensors_.heading_deg;
}

BatteryVolts SharedRobotIo::battery() const {
  const std::lock_guard lock(mutex_);
  return sensors_.battery;
}

void SharedRobotIo::apply_commands() {
  std::array<std::optional<double>, 3> wheel;
  std::optional<int> grabber;
  std::vector<std::pair<bool, int>> kicks;
  {
    const std::lock_guard lock(mutex_);
    wheel = wheel_;
    grabber = grabber_;
    kicks.swap(kicks_);
  }
  for (std::size_t w = 0; w < wheel.size(); ++w) {
    if (wheel[w]) robot_.set_wheel_speed(static_cast<int>(w), *wheel[w]);
  }
  if (grabber) robot_.set_grabber(*grabber);
  for (const auto& [low, power] : kicks) robot_.kick(low, power);
}

void SharedRobotIo::publish() {
  const PhysicsRobotIo direct(robot_);
  Sensors s;
  for (int w = 0; w < 3; ++w) {
    const auto i = static_cast<std::size_t>(w);
    s.encoder[i] = direct.encoder_count(w);
    s.stalled[i] = direct.wheel_stalled(w);
    s.over_current[i] = direct.over_current(w);
  }
  s.engaged = direct.ball_engaged();
  s.kicker_v = direct.kicker_voltage_v();
  s.heading_deg = direct.compass_heading_deg();
  s.battery = direct.battery();
  const std::lock_guard lock(mutex_);
  sensors_ = s;
}

}  // namespace canhil::emulator
