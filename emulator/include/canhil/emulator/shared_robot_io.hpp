// canhil/emulator/shared_robot_io.hpp — one robot's I/O shared between the
// node thread and the physics thread of a real-time run.
//
// The nodes must never wait for a physics step (their frames would be late by
// it), so they never touch the world: they read the sensor values the physics
// thread published after its last step, and leave their commands (wheel
// speeds, grabber, kicks) to be applied before its next one. One mutex guards
// both sides; each critical section copies a few numbers. A kick's outcome is
// decided from the published state (power, barrier, capacitor) the way the
// physics decides it, and the kick itself fires at the next step.
#pragma once

#include <array>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "canhil/base/pi_mutex.hpp"
#include "canhil/can_nodes/robot_io.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::emulator {

class SharedRobotIo final : public can_nodes::RobotIo {
 public:
  /// Publishes the robot's state once; `robot` must outlive this.
  explicit SharedRobotIo(physics::Robot& robot);

  // can_nodes::RobotIo: the node thread.
  void set_wheel_speed(int wheel, double radps) override;
  std::int64_t encoder_count(int wheel) const override;
  bool wheel_stalled(int wheel) const override;
  bool over_current(int wheel) const override;
  KickOutcome kick(bool low, int power) override;
  void set_grabber(int mode) override;
  bool ball_engaged() const override;
  double kicker_voltage_v() const override;
  double compass_heading_deg() const override;
  BatteryVolts battery() const override;

  // The physics thread.
  /// Before a step: the latest wheel speeds and grabber mode, and the kicks asked for since.
  void apply_commands();
  /// After a step: the sensor values the nodes will read.
  void publish();

 private:
  struct Sensors {
    std::array<std::int64_t, 3> encoder{};
    std::array<bool, 3> stalled{}, over_current{};
    bool engaged = false;
    double kicker_v = 0;
    double heading_deg = 0;
    BatteryVolts battery;
  };
  physics::Robot& robot_;
  const physics::KickerParams kicker_;
  mutable PiMutex mutex_;  // the node thread is SCHED_FIFO, the physics thread is not
  Sensors sensors_;
  std::array<std::optional<double>, 3> wheel_;
  std::optional<int> grabber_;
  std::vector<std::pair<bool, int>> kicks_;
};

}  // namespace canhil::emulator
