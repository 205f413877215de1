#include <ode/ode.h>

#include <algorithm>
#include <cmath>

#include "canhil/base/demand.hpp"
#include "canhil/physics/world.hpp"
#include "world_impl.hpp"

namespace canhil::physics {

using detail::vec;

// ---------------------------------------------------------------------------
// Robot

Robot::Robot(std::unique_ptr<RobotImpl> impl) : impl_(std::move(impl)) {}
Robot::~Robot() = default;
const RobotParams& Robot::params() const { return *impl_->params; }

namespace {
std::size_t wheel_index(int wheel) {
  CANHIL_DEMAND(wheel >= 0 && wheel < 3, "wheel index must be 0, 1 or 2");
  return static_cast<std::size_t>(wheel);
}
}  // namespace

void Robot::set_wheel_speed(int wheel, double radps) {
  const std::size_t n = wheel_index(wheel);
  impl_->state.wheel_target_radps[n] = std::isfinite(radps) ? radps : 0.0;
}
void Robot::brake() {
  for (int n = 0; n < 3; ++n) set_wheel_speed(n, 0.0);
}
double Robot::wheel_angle_rad(int wheel) const { return impl_->state.wheel_angle_rad[wheel_index(wheel)]; }
double Robot::wheel_speed_radps(int wheel) const { return dJointGetHingeAngleRate(impl_->hinge[wheel_index(wheel)]); }
std::int64_t Robot::encoder_count(int wheel) const {
  return static_cast<std::int64_t>(std::floor(impl_->params->encoder.counts(wheel_angle_rad(wheel))));
}
double Robot::motor_current_a(int wheel) const { return impl_->state.motor_current_a[wheel_index(wheel)]; }
bool Robot::over_current(int wheel) const {
  return std::fabs(motor_current_a(wheel)) >= 0.98 * impl_->params->motor.current_limit_a;
}
bool Robot::wheel_stalled(int wheel) const {
  const std::size_t n = wheel_index(wheel);
  const double stall = impl_->params->motor.stall_speed_radps;
  const bool commanded = std::fabs(impl_->state.wheel_target_radps[n]) > stall;
  return commanded && std::fabs(wheel_speed_radps(wheel)) < stall && over_current(wheel);
}

bool Robot::ball_engaged() const {
  const BarrierParams& b = impl_->params->barrier;
  const Eigen::Vector3d centre = vec(dBodyGetPosition(impl_->chassis));
  const Eigen::Vector3d ball = vec(dBodyGetPosition(impl_->world->ball));
  Eigen::Vector3d d = ball - centre;
  d.z() = 0;
  const double dist = d.norm();
  if (dist > b.max_distance_m || ball.z() > b.max_height_m) return false;
  if (dist < 1e-9) return true;
  const double bearing = std::acos(std::clamp(d.dot(impl_->front()) / dist, -1.0, 1.0));
  return bearing <= b.half_angle_deg * detail::kPi / 180.0;
}

KickOutcome kick_outcome(const KickerParams& kicker, int power, bool ball_engaged, double kicker_voltage_v) noexcept {
  if (std::clamp(power, 0, kicker.max_power) == 0) return KickOutcome::kNoPower;
  if (!ball_engaged) return KickOutcome::kNotEngaged;
  if (kicker_voltage_v < kicker.min_fire_voltage_v) return KickOutcome::kLowVoltage;
  return KickOutcome::kFired;
}

KickResult Robot::kick(bool low, int power) {
  const KickerParams& k = impl_->params->kicker;
  KickResult result;
  RobotState& st = impl_->state;
  result.outcome = kick_outcome(k, power, ball_engaged(), st.kicker_voltage_v);
  if (!result.fired()) return result;
  const int p = std::clamp(power, 0, k.max_power);
  const double g = impl_->world->params.simulation.gravity_mps2;
  const double theta = k.lob_angle_deg * detail::kPi / 180.0;
  const double v_max = std::sqrt(k.max_lob_range_m * g / std::sin(2.0 * theta));
  const double speed = v_max * p / k.max_power * (st.kicker_voltage_v / k.full_voltage_v);
  const Eigen::Vector3d front = impl_->front();
  Eigen::Vector3d launch = low ? Eigen::Vector3d(front * speed)
                               : Eigen::Vector3d(front.x() * std::cos(theta) * speed,
                                                 front.y() * std::cos(theta) * speed, std::sin(theta) * speed);
  // The kick adds to the robot's own motion at the ball.
  const Eigen::Vector3d ball = vec(dBodyGetPosition(impl_->world->ball));
  dVector3 v_at_ball;
  dBodyGetPointVel(impl_->chassis, ball.x(), ball.y(), ball.z(), v_at_ball);
  launch += Eigen::Vector3d(v_at_ball[0], v_at_ball[1], 0);
  dBodySetLinearVel(impl_->world->ball, launch.x(), launch.y(), launch.z());
  dBodySetAngularVel(impl_->world->ball, 0, 0, 0);
  st.kicker_voltage_v *= std::sqrt(std::max(0.0, 1.0 - k.energy_per_full_kick * p / k.max_power));
  st.grabber_release_left_s = k.grabber_release_s;
  st.last_kick_time_s = impl_->world->time;
  result.speed_mps = speed;
  return result;
}

void Robot::set_grabber(int mode) { impl_->state.grabber_mode = std::clamp(mode, 0, 100); }
int Robot::grabber_mode() const { return impl_->state.grabber_mode; }
double Robot::kicker_voltage_v() const { return impl_->state.kicker_voltage_v; }
double Robot::last_kick_time_s() const { return impl_->state.last_kick_time_s; }

double Robot::compass_heading_deg() const {
  const double front_yaw_deg = (impl_->yaw() + detail::kPi / 2) * 180.0 / detail::kPi;
  double h = std::fmod(impl_->params->compass.north_offset_deg - front_yaw_deg, 360.0);
  if (h < 0) h += 360.0;
  return h >= 360.0 ? 0.0 : h;
}

BatteryVolts Robot::battery() const {
  const BatteryParams& bp = impl_->params->battery;
  const RobotState& st = impl_->state;
  double motors = 0;
  for (double i : st.motor_current_a) motors += std::fabs(i);
  auto volts = [&](const RailParams& r, double charge, double current) {
    return std::max(0.0, r.empty_v + (r.full_v - r.empty_v) * charge - current * r.internal_resistance_ohm);
  };
  return BatteryVolts{volts(bp.logic, st.charge[0], bp.logic.base_current_a),
                      volts(bp.power12, st.charge[1], bp.power12.base_current_a),
                      volts(bp.power24, st.charge[2], bp.power24.base_current_a + motors)};
}

std::array<double, 3> Robot::charge() const { return impl_->state.charge; }

void Robot::drain(const std::array<double, 3>& fraction) {
  for (std::size_t i = 0; i < fraction.size(); ++i) {
    impl_->state.charge[i] = std::clamp(impl_->state.charge[i] - fraction[i], 0.0, 1.0);
  }
}

kinematics::Pose Robot::pose() const {
  const dReal* p = dBodyGetPosition(impl_->chassis);
  return kinematics::Pose{p[0], p[1], impl_->yaw()};
}

kinematics::Twist Robot::twist() const {
  const dReal* v = dBodyGetLinearVel(impl_->chassis);
  const dReal* w = dBodyGetAngularVel(impl_->chassis);
  const double yaw = impl_->yaw();
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  return kinematics::Twist{c * v[0] + s * v[1], -s * v[0] + c * v[1], w[2]};
}

void Robot::place(const Placement& at) {
  RobotImpl& r = *impl_;
  const double yaw = at.heading_deg * detail::kPi / 180.0;
  dMatrix3 rot;
  dRFromAxisAndAngle(rot, 0, 0, 1, yaw);
  dBodySetPosition(r.chassis, at.x_m, at.y_m, r.z_body);
  dBodySetRotation(r.chassis, rot);
  dBodySetLinearVel(r.chassis, 0, 0, 0);
  dBodySetAngularVel(r.chassis, 0, 0, 0);
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  const RobotParams& p = *r.params;
  for (std::size_t n = 0; n < 3; ++n) {
    const double phi = p.geometry.wheel_angles_deg[n] * detail::kPi / 180.0;
    const double lx = p.geometry.wheel_distance_m * std::cos(phi);
    const double ly = p.geometry.wheel_distance_m * std::sin(phi);
    const double wz = p.geometry.wheel_radius_m;
    dBodySetPosition(r.wheel[n], at.x_m + c * lx - s * ly, at.y_m + s * lx + c * ly, wz);
    dBodySetRotation(r.wheel[n], rot);
    dBodySetLinearVel(r.wheel[n], 0, 0, 0);
    dBodySetAngularVel(r.wheel[n], 0, 0, 0);
    // Re-attach so the hinge's reference angle is this pose.
    dJointAttach(r.hinge[n], r.wheel[n], r.chassis);
    dJointSetHingeAnchor(r.hinge[n], at.x_m + c * lx - s * ly, at.y_m + s * lx + c * ly, wz);
    const Eigen::Vector3d& a = r.axle_body[n];
    dJointSetHingeAxis(r.hinge[n], c * a.x() - s * a.y(), s * a.x() + c * a.y(), a.z());
    dJointSetHingeParam(r.hinge[n], dParamFMax, 0);
    r.state.hinge_angle_rad[n] = dJointGetHingeAngle(r.hinge[n]);
  }
  r.world->canon_of(r.chassis).capture();
  for (dBodyID w : r.wheel) r.world->canon_of(w).capture();
}

}  // namespace canhil::physics
