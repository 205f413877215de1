// canhil/kinematics/omni.hpp — kinematics of a three-wheeled omnidirectional base.
//
// Pure math, no physics engine, no CAN: used by the physics tests and
// experiments and by the emulated Pic_base (inverse) and Pic_odom (forward).
//
// Robot frame: +y is the robot's front, +x its right, angles counter-clockwise.
// Wheel n sits at angle phi_n from +x at distance b from the centre and drives
// along F_n = (-sin phi_n, cos phi_n); with the default phi = 30, 150, 270 deg:
// F1 = (-1/2, sqrt3/2), F2 = (-1/2, -sqrt3/2), F3 = (1, 0).
// Inverse kinematics: w_n = (V . F_n + b * w) / r  (wheel speeds in rad/s).
#pragma once

#include <array>
#include <cstdint>

#include "canhil/base/setup_error.hpp"

namespace canhil::kinematics {

/// Velocity of the base in its own frame.
struct Twist {
  double vx_mps = 0;    ///< right
  double vy_mps = 0;    ///< forward
  double va_radps = 0;  ///< counter-clockwise
};

using WheelSpeeds = std::array<double, 3>;  ///< rad/s, positive = drives the base along F_n

struct OmniGeometry {
  double wheel_radius_m = 0.0573;
  double wheel_distance_m = 0.19;  ///< b, centre to wheel contact
  std::array<double, 3> wheel_angles_deg = {30.0, 150.0, 270.0};

  friend bool operator==(const OmniGeometry&, const OmniGeometry&) = default;
};

/// The base's inverse and forward kinematics; immutable once built.
class OmniKinematics {
 public:
  /// Throws SetupError if the geometry is degenerate (radius or
  /// distance not positive, wheels not spanning the plane).
  explicit OmniKinematics(const OmniGeometry& geometry = {});

  const OmniGeometry& geometry() const noexcept { return geometry_; }
  /// F_n, the drive direction of wheel n (0-based) in the robot frame.
  std::array<double, 2> drive_direction(int wheel) const noexcept { return drive_[static_cast<std::size_t>(wheel)]; }

  WheelSpeeds inverse(const Twist& twist) const noexcept;
  Twist forward(const WheelSpeeds& wheels) const noexcept;

 private:
  OmniGeometry geometry_;
  std::array<std::array<double, 2>, 3> drive_{};
  std::array<std::array<double, 3>, 3> forward_{};  // inverse of the 3x3 [F_n^T b] / r matrix
};

/// The motor's encoder and gear: counts per wheel turn and the motor tick.
struct EncoderSpec {
  int pulses_per_rev = 500;  ///< encoder lines per motor turn
  int quadrature = 4;        ///< edges counted per line
  double gear_ratio = 15.0;  ///< motor turns per wheel turn
  double motor_tick_s = 0.005;

  double counts_per_wheel_rev() const noexcept { return pulses_per_rev * quadrature * gear_ratio; }
  /// Wheel speed (rad/s) to encoder counts per motor tick, unrounded.
  double counts_per_tick(double wheel_radps) const noexcept;
  double wheel_radps(double counts_per_tick) const noexcept;
  /// Wheel angle (rad) to encoder counts, unrounded.
  double counts(double wheel_angle_rad) const noexcept;
  double wheel_angle_rad(double counts) const noexcept;

  friend bool operator==(const EncoderSpec&, const EncoderSpec&) = default;
};

/// A planar pose, world frame: heading is the angle of the robot's +x axis
/// from the world's +x axis (counter-clockwise); its front (+y) then points at
/// heading + 90 deg.
struct Pose {
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;
};

/// Integrates a robot-frame twist over dt (exact for constant twist: arc motion).
Pose integrate(const Pose& pose, const Twist& twist, double dt_s) noexcept;

/// Wraps an angle to (-pi, pi].
double wrap_pi(double angle_rad) noexcept;

}  // namespace canhil::kinematics
