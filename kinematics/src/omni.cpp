#include "canhil/kinematics/omni.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "canhil/base/setup_error.hpp"

namespace canhil::kinematics {

OmniKinematics::OmniKinematics(const OmniGeometry& geometry) : geometry_(geometry) {
  if (!(geometry.wheel_radius_m > 0) || !(geometry.wheel_distance_m > 0)) {
    throw SetupError("wheel radius and wheel distance must be positive");
  }
  const double r = geometry.wheel_radius_m;
  const double b = geometry.wheel_distance_m;
  // Rows of the inverse-kinematics matrix A (w = A v): (F_nx, F_ny, b) / r.
  std::array<std::array<double, 3>, 3> a{};
  for (std::size_t n = 0; n < 3; ++n) {
    const double phi = geometry.wheel_angles_deg[n] * std::numbers::pi / 180.0;
    drive_[n] = {-std::sin(phi), std::cos(phi)};
    a[n] = {drive_[n][0] / r, drive_[n][1] / r, b / r};
  }
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  if (std::fabs(det) < 1e-9) throw SetupError("wheel angles do not span the plane (singular kinematics)");
  // Adjugate / determinant.
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) {
      const std::size_t r1 = (j + 1) % 3;
      const std::size_t r2 = (j + 2) % 3;
      const std::size_t c1 = (i + 1) % 3;
      const std::size_t c2 = (i + 2) % 3;
      forward_[i][j] = (a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1]) / det;
    }
  }
}

WheelSpeeds OmniKinematics::inverse(const Twist& t) const noexcept {
  WheelSpeeds w{};
  for (std::size_t n = 0; n < 3; ++n) {
    w[n] = (t.vx_mps * drive_[n][0] + t.vy_mps * drive_[n][1] + geometry_.wheel_distance_m * t.va_radps) /
           geometry_.wheel_radius_m;
  }
  return w;
}

Twist OmniKinematics::forward(const WheelSpeeds& w) const noexcept {
  std::array<double, 3> v{};
  for (std::size_t i = 0; i < 3; ++i) v[i] = forward_[i][0] * w[0] + forward_[i][1] * w[1] + forward_[i][2] * w[2];
  return Twist{v[0], v[1], v[2]};
}

double EncoderSpec::counts_per_tick(double wheel_radps) const noexcept {
  return wheel_radps * motor_tick_s * counts_per_wheel_rev() / (2.0 * std::numbers::pi);
}
double EncoderSpec::wheel_radps(double counts_per_tick_value) const noexcept {
  return counts_per_tick_value * 2.0 * std::numbers::pi / (motor_tick_s * counts_per_wheel_rev());
}
double EncoderSpec::counts(double wheel_angle) const noexcept {
  return wheel_angle * counts_per_wheel_rev() / (2.0 * std::numbers::pi);
}
double EncoderSpec::wheel_angle_rad(double c) const noexcept {
  return c * 2.0 * std::numbers::pi / counts_per_wheel_rev();
}

double wrap_pi(double a) noexcept {
  a = std::remainder(a, 2.0 * std::numbers::pi);  // [-pi, pi]
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

Pose integrate(const Pose& p, const Twist& t, double dt) noexcept {
  // Robot-frame velocity to world frame at the start heading, then exact arc.
  const double th = p.heading_rad;
  const double dth = t.va_radps * dt;
  double fx = dt;  // integral of cos/sin factors: sin(dth)/w and (1-cos(dth))/w
  double gx = 0;
  if (std::fabs(dth) > 1e-12) {
    fx = std::sin(dth) / t.va_radps;
    gx = (1.0 - std::cos(dth)) / t.va_radps;
  }
  // Displacement in the start frame: R(s) integrated.
  const double dx_r = t.vx_mps * fx - t.vy_mps * gx;
  const double dy_r = t.vx_mps * gx + t.vy_mps * fx;
  Pose out;
  out.x_m = p.x_m + std::cos(th) * dx_r - std::sin(th) * dy_r;
  out.y_m = p.y_m + std::sin(th) * dx_r + std::cos(th) * dy_r;
  out.heading_rad = wrap_pi(th + dth);
  return out;
}

}  // namespace canhil::kinematics
