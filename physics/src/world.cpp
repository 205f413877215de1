#include "canhil/physics/world.hpp"

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "canhil/base/demand.hpp"
#include "canhil/base/setup_error.hpp"
#include "solver_scope.hpp"
#include "world_impl.hpp"

namespace canhil::physics {
namespace {

using detail::Canon;
using detail::Kind;
using detail::Tag;
using detail::vec;

constexpr int kMaxContacts = 8;

BodyState read_body(const Canon& c) {
  dBodyID b = c.body;
  BodyState s;
  const dReal* p = dBodyGetPosition(b);
  const std::array<double, 4>& q = c.q_in;
  const dReal* v = dBodyGetLinearVel(b);
  const dReal* w = dBodyGetAngularVel(b);
  for (std::size_t i = 0; i < 3; ++i) {
    s.position[i] = p[i];
    s.linear_velocity[i] = v[i];
    s.angular_velocity[i] = w[i];
  }
  for (std::size_t i = 0; i < 4; ++i) s.quaternion[i] = q[i];
  s.enabled = dBodyIsEnabled(b) != 0;
  return s;
}

void write_body(Canon& c, const BodyState& s) {
  dBodyID b = c.body;
  dBodySetPosition(b, s.position[0], s.position[1], s.position[2]);
  c.q_in = s.quaternion;
  c.apply();
  dBodySetLinearVel(b, s.linear_velocity[0], s.linear_velocity[1], s.linear_velocity[2]);
  dBodySetAngularVel(b, s.angular_velocity[0], s.angular_velocity[1], s.angular_velocity[2]);
  dBodySetForce(b, 0, 0, 0);
  dBodySetTorque(b, 0, 0, 0);
  if (s.enabled) {
    dBodyEnable(b);
  } else {
    dBodyDisable(b);
  }
}

}  // namespace

// ---------------------------------------------------------------------------
// Stepping

double RobotImpl::supply_v() const {
  const RailParams& rail = params->battery.power24;
  return rail.empty_v + (rail.full_v - rail.empty_v) * state.charge[2];
}

void World::Impl::apply_robot_inputs(RobotImpl& r) {
  const MotorParams& mp = r.params->motor;
  const double gear = r.params->encoder.gear_ratio;
  const double k = mp.torque_constant_nm_per_a;  // = back-EMF constant in SI
  const double v_supply = r.supply_v();
  for (std::size_t n = 0; n < 3; ++n) {
    const double w = dJointGetHingeAngleRate(r.hinge[n]);
    const double w_motor = w * gear;
    // The controller reaches the target within what the motor can give:
    // current limit, and the supply minus back-EMF when driving.
    const double target = r.state.wheel_target_radps[n];
    const bool driving = (target - w) * w > 0;
    double i_max = mp.current_limit_a;
    if (driving)
      i_max = std::min(i_max, std::max(0.0, (v_supply - k * std::fabs(w_motor)) / mp.terminal_resistance_ohm));
    dJointSetHingeParam(r.hinge[n], dParamVel, target);
    dJointSetHingeParam(r.hinge[n], dParamFMax, i_max * k * gear * mp.gear_efficiency);
  }
  apply_grabber(r);
}

void World::Impl::apply_grabber(RobotImpl& r) {
  const GrabberParams& g = r.params->grabber;
  if (r.state.grabber_mode <= 0 || r.state.grabber_release_left_s > 0) return;
  const Eigen::Vector3d centre = vec(dBodyGetPosition(r.chassis));
  const Eigen::Vector3d ball_pos = vec(dBodyGetPosition(ball));
  Eigen::Vector3d d = ball_pos - centre;
  d.z() = 0;
  const double dist = d.norm();
  if (dist > g.range_m || dist < 1e-9) return;
  const Eigen::Vector3d front = r.front();
  const double bearing = std::acos(std::clamp(d.dot(front) / dist, -1.0, 1.0));
  if (bearing > g.half_angle_deg * detail::kPi / 180.0) return;
  if (ball_pos.z() > r.params->barrier.max_height_m + params.ball.radius_m) return;
  // Pull towards the back of the mouth.
  const double hold = r.params->body_radius_m - r.params->mouth_depth_m + params.ball.radius_m;
  Eigen::Vector3d target = centre + front * hold;
  Eigen::Vector3d pull = target - ball_pos;
  pull.z() = 0;
  const double len = pull.norm();
  if (len < 1e-4) return;
  const double force = g.max_force_n * r.state.grabber_mode / 100.0;
  const Eigen::Vector3d f = pull / len * force;
  dBodyAddForce(ball, f.x(), f.y(), 0);
  dBodyAddForce(r.chassis, -f.x(), -f.y(), 0);
}

void World::Impl::update_robot_after(RobotImpl& r, double h) {
  const MotorParams& mp = r.params->motor;
  const double gear = r.params->encoder.gear_ratio;
  const double k = mp.torque_constant_nm_per_a;
  double motor_current = 0;
  for (std::size_t n = 0; n < 3; ++n) {
    const double angle = dJointGetHingeAngle(r.hinge[n]);
    r.state.wheel_angle_rad[n] += kinematics::wrap_pi(angle - r.state.hinge_angle_rad[n]);
    r.state.hinge_angle_rad[n] = angle;
    // Motor torque from the hinge's feedback, about the axle (in world coordinates).
    const Eigen::Vector3d axle = r.axle_world(n);
    const Eigen::Vector3d t1(r.feedback[n].t1[0], r.feedback[n].t1[1], r.feedback[n].t1[2]);
    r.state.motor_current_a[n] = t1.dot(axle) / (k * gear * mp.gear_efficiency);
    motor_current += std::fabs(r.state.motor_current_a[n]);
  }
  // Kicker recharge and the grabber's release after a kick.
  const KickerParams& kp = r.params->kicker;
  r.state.kicker_voltage_v +=
      (kp.full_voltage_v - r.state.kicker_voltage_v) * (1.0 - std::exp(-h / kp.recharge_time_constant_s));
  r.state.grabber_release_left_s = std::max(0.0, r.state.grabber_release_left_s - h);
  // Battery drain (ampere-hours).
  const BatteryParams& bp = r.params->battery;
  const std::array<const RailParams*, 3> rails = {&bp.logic, &bp.power12, &bp.power24};
  for (std::size_t i = 0; i < 3; ++i) {
    const double current = rails[i]->base_current_a + (i == 2 ? motor_current : 0.0);
    r.state.charge[i] = std::max(0.0, r.state.charge[i] - current * h / 3600.0 / rails[i]->capacity_ah);
  }
}

void World::Impl::collide(dGeomID a, dGeomID b) {
  const Tag* ta = static_cast<const Tag*>(dGeomGetData(a));
  const Tag* tb = static_cast<const Tag*>(dGeomGetData(b));
  if (ta == nullptr || tb == nullptr) return;
  dBodyID ba = dGeomGetBody(a);
  dBodyID bb = dGeomGetBody(b);
  if (ba == nullptr && bb == nullptr) return;
  if (ba != nullptr && bb != nullptr && dAreConnectedExcluding(ba, bb, dJointTypeContact)) return;
  // Order so that `ta` is the lower kind (ground < static < ball < chassis < wheel < obstacle).
  if (tb->kind < ta->kind) {
    std::swap(a, b);
    std::swap(ta, tb);
    std::swap(ba, bb);
  }
  // A sleeping body against the static world needs no contacts; ODE wakes it
  // when an awake body's contact joint reaches it.
  const bool a_awake = ba != nullptr && dBodyIsEnabled(ba) != 0;
  const bool b_awake = bb != nullptr && dBodyIsEnabled(bb) != 0;
  if (!a_awake && !b_awake) return;
  dContact c[kMaxContacts];
  // Four points hold a body resting on the carpet; more only cost solver rows.
  const int cap = (ta->kind == Kind::kGround && tb->kind == Kind::kObstacle) ? 4 : kMaxContacts;
  const int n = collide_hulls(a, b, cap, &c[0].geom, sizeof(dContact));
  if (n == 0) return;
  const BallParams& bp = params.ball;
  const RobotParams& rp = params.robot;
  for (int i = 0; i < n; ++i) {
    dSurfaceParameters& s = c[i].surface;
    s.mode = dContactSoftCFM | dContactSoftERP | dContactApprox1;
    s.soft_cfm = 1e-5;
    s.soft_erp = 0.4;
    s.mu = params.field.ground_friction;
    if (tb->kind == Kind::kBall || ta->kind == Kind::kBall) {
      s.mode |= dContactBounce;
      s.bounce = ta->kind == Kind::kGround ? bp.restitution : 0.5;
      s.bounce_vel = bp.bounce_min_speed_mps;
      s.mu = bp.friction;
      if (ta->kind == Kind::kGround) {
        ball_on_ground = true;
        // Rolling resistance as a contact constraint: it acts only while the ball
        // touches the carpet (never in flight) and brings it fully to rest.
        // Torque limit rho * N with rho chosen so the rolling deceleration is
        // rolling_resistance * g for a shell (I = 2/3 m r^2).
        s.mode |= dContactRolling;
        s.rho = bp.rolling_resistance * bp.radius_m * (1.0 + 2.0 / 3.0);
        s.rho2 = s.rho;
        s.rhoN = bp.spin_damping * 1e-3;
      }
    } else if (tb->kind == Kind::kWheel) {
      // Omni wheel: grips along its drive direction, rolls freely across it.
      const RobotImpl& r = robot(static_cast<std::size_t>(tb->owner));
      const Eigen::Vector3d axle = r.axle_world(static_cast<std::size_t>(tb->wheel));
      const Eigen::Vector3d normal(c[i].geom.normal[0], c[i].geom.normal[1], c[i].geom.normal[2]);
      Eigen::Vector3d roll = axle.cross(normal);
      if (roll.norm() < 1e-6) continue;
      roll.normalize();
      s.mode |= dContactMu2 | dContactFDir1;
      s.mu = rp.wheel_friction;
      s.mu2 = rp.wheel_cross_friction;
      c[i].fdir1[0] = roll.x();
      c[i].fdir1[1] = roll.y();
      c[i].fdir1[2] = roll.z();
      s.soft_erp = 0.6;
    } else if (ta->kind == Kind::kGround && tb->kind == Kind::kObstacle) {
      s.mu = params.obstacles[static_cast<std::size_t>(tb->owner)].params.friction;
    } else if (ta->kind == Kind::kChassis || ta->kind == Kind::kObstacle) {
      s.mu = 0.4;  // bodies sliding along each other
    }
    dJointID j = dJointCreateContact(world, contacts, &c[i]);
    dJointAttach(j, ba, bb);
    ++contact_points;
    // Rows: the normal, two of friction, three of rolling resistance.
    islands.link(index_of(ba), index_of(bb), (s.mode & dContactRolling) != 0 ? 6 : 3);
  }
}

namespace {
int tag_id(dGeomID g) { return static_cast<const Tag*>(dGeomGetData(g))->id; }

void near_callback(void* data, dGeomID a, dGeomID b) {
  auto* impl = static_cast<World::Impl*>(data);
  if (dGeomIsSpace(a) != 0 || dGeomIsSpace(b) != 0) {
    // A robot's own space against something else: its parts never touch each other.
    dSpaceCollide2(a, b, data, &near_callback);
    return;
  }
  auto ia = static_cast<std::uint32_t>(tag_id(a));
  auto ib = static_cast<std::uint32_t>(tag_id(b));
  if (ib < ia) {
    std::swap(a, b);
    std::swap(ia, ib);
  }
  impl->pairs.push_back({(std::uint64_t{ia} << 32U) | ib, a, b});
}
}  // namespace

void World::Impl::substep(double h) {
  for (std::size_t i = 0; i < robots.size(); ++i) apply_robot_inputs(robot(i));
  ball_on_ground = false;
  islands.reset(canon.size());
  for (std::size_t i = 0; i < robots.size(); ++i) {
    // A motorised hinge: five rows and the motor's.
    for (dBodyID w : robot(i).wheel) islands.link(index_of(robot(i).chassis), index_of(w), 6);
  }
  pairs.clear();
  dSpaceCollide(dynamics, this, &near_callback);
  dSpaceCollide2(reinterpret_cast<dGeomID>(dynamics), reinterpret_cast<dGeomID>(statics), this, &near_callback);
  // ODE's spaces reorder geoms as they move; contacts are made in creation-id
  // order so that the solver sees the same rows whatever the history.
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.order < y.order; });
  for (const Pair& p : pairs) collide(p.a, p.b);
  // ODE shuffles constraint order with a global seed: keep this world's own.
  dRandSetSeed(seed);
  const SimulationParams& sp = params.simulation;
  if (!sp.exact_solver) {
    dWorldQuickStep(world, h);
  } else if (sp.exact_solver_max_rows <= 0 || islands.largest() <= sp.exact_solver_max_rows) {
    dWorldStep(world, h);
  } else {
    step_split(h);
  }
  seed = dRandGetSeed();
  dJointGroupEmpty(contacts);
  for (std::size_t i = 0; i < robots.size(); ++i) update_robot_after(robot(i), h);
  time += h;
}

// Islands of more than exact_solver_max_rows rows by QuickStep, the rest
// exactly: ODE steps only enabled bodies, and an island is stepped whole, so
// each pass disables the other pass's bodies and the enabled flags are put
// back as ODE would have left them (a large island's bodies all awake).
void World::Impl::step_split(double h) {
  ++split_substeps;
  const std::size_t n = canon.size();
  big.assign(n, 0);
  was_enabled.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    big[i] = islands.rows_of(static_cast<int>(i)) > params.simulation.exact_solver_max_rows ? 1 : 0;
    if (big[i] != 0) dBodyDisable(canon[i].body);
  }
  dWorldStep(world, h);
  for (std::size_t i = 0; i < n; ++i) {
    dBodyID b = canon[i].body;
    if (big[i] != 0) {
      dBodyEnable(b);
    } else if (dBodyIsEnabled(b) != 0) {
      was_enabled[i] = 1;
      dBodyDisable(b);
    }
  }
  dWorldQuickStep(world, h);
  for (std::size_t i = 0; i < n; ++i) {
    if (was_enabled[i] != 0) dBodyEnable(canon[i].body);
  }
}

// ---------------------------------------------------------------------------
// World

namespace {
// Bodies that start inside each other are shot apart by the contact solver:
// refuse such a start with a message that says which and where.
void check_start_positions(const WorldParams& p) {
  struct Disc {
    std::string what;
    double x, y, r;
  };
  std::vector<Disc> discs;
  for (std::size_t i = 0; i < p.robots.size(); ++i) {
    discs.push_back({"robot " + std::to_string(i), p.robots[i].x_m, p.robots[i].y_m, p.robot.body_radius_m});
  }
  for (std::size_t i = 0; i < p.obstacles.size(); ++i) {
    discs.push_back({"obstacle " + std::to_string(i), p.obstacles[i].at.x_m, p.obstacles[i].at.y_m,
                     p.obstacles[i].params.radius_m});
  }
  const double ball_r = p.ball.radius_m;
  // A ball held in a robot's mouth (the front cut-out) is inside its disc but not its body.
  auto in_mouth = [&](std::size_t robot) {
    const double yaw = p.robots[robot].heading_deg * detail::kPi / 180.0;
    const double dx = p.ball_start.x_m - p.robots[robot].x_m;
    const double dy = p.ball_start.y_m - p.robots[robot].y_m;
    const double across = std::cos(yaw) * dx + std::sin(yaw) * dy;  // robot frame, +x
    const double ahead = -std::sin(yaw) * dx + std::cos(yaw) * dy;  // robot frame, +y (front)
    return std::fabs(across) + ball_r <= p.robot.mouth_width_m / 2 + 1e-9 &&
           ahead >= p.robot.body_radius_m - p.robot.mouth_depth_m + ball_r - 1e-9;
  };
  for (std::size_t i = 0; i < discs.size(); ++i) {
    const Disc& a = discs[i];
    const bool held = i < p.robots.size() && in_mouth(i);
    if (p.ball_start.z_m < 1.0 && !held &&
        std::hypot(a.x - p.ball_start.x_m, a.y - p.ball_start.y_m) < a.r + ball_r - 1e-9) {
      throw SetupError("ball_start (" + std::to_string(p.ball_start.x_m) + ", " + std::to_string(p.ball_start.y_m) +
                       ") is inside " + a.what + "; move the ball or the " + a.what.substr(0, a.what.find(' ')));
    }
    for (std::size_t j = i + 1; j < discs.size(); ++j) {
      const Disc& b = discs[j];
      if (std::hypot(a.x - b.x, a.y - b.y) < a.r + b.r - 1e-9) {
        throw SetupError(a.what + " and " + b.what + " start overlapping; place them further apart");
      }
    }
  }
}
}  // namespace

World::World(WorldParams params) : impl_((check_start_positions(params), std::make_unique<Impl>(std::move(params)))) {}
World::~World() = default;
const WorldParams& World::params() const noexcept { return impl_->params; }
const FieldMarkings& World::markings() const noexcept { return impl_->markings; }
double World::time_s() const noexcept { return impl_->time; }
const SolverHealth& World::solver_health() const noexcept { return impl_->solver; }
std::uint64_t World::large_island_substeps() const noexcept { return impl_->split_substeps; }
std::uint64_t World::contact_points() const noexcept { return impl_->contact_points; }
std::size_t World::robot_count() const noexcept { return impl_->robots.size(); }
Robot& World::robot(std::size_t i) { return *impl_->robots.at(i); }
const Robot& World::robot(std::size_t i) const { return *impl_->robots.at(i); }
Eigen::Vector3d World::ball_position() const { return vec(dBodyGetPosition(impl_->ball)); }
Eigen::Vector3d World::ball_velocity() const { return vec(dBodyGetLinearVel(impl_->ball)); }
bool World::ball_on_ground() const noexcept { return impl_->ball_on_ground; }
std::size_t World::obstacle_count() const noexcept { return impl_->obstacle_geoms.size(); }
const ObstacleParams& World::obstacle_params(std::size_t i) const { return impl_->params.obstacles.at(i).params; }

Eigen::Vector3d World::obstacle_position(std::size_t i) const {
  return vec(dGeomGetPosition(impl_->obstacle_geoms.at(i)));
}

void World::step() {
  const detail::SolverScope scope(impl_->solver, impl_->time);
  const SimulationParams& s = impl_->params.simulation;
  const double h = s.step_s / s.substeps;
  for (int k = 0; k < s.substeps; ++k) impl_->substep(h);
  for (Canon& c : impl_->canon) c.capture();
  // Movable obstacles at rest leave the solver until touched.
  if (s.sleep_after_steps <= 0) return;
  for (std::size_t i = 0; i < impl_->obstacle_bodies.size(); ++i) {
    dBodyID b = impl_->obstacle_bodies[i];
    if (b == nullptr || dBodyIsEnabled(b) == 0) {
      impl_->obstacle_idle[i] = 0;
      continue;
    }
    const Eigen::Vector3d v = vec(dBodyGetLinearVel(b));
    const Eigen::Vector3d w = vec(dBodyGetAngularVel(b));
    impl_->obstacle_idle[i] = (v.norm() < 0.01 && w.norm() < 0.05) ? impl_->obstacle_idle[i] + 1 : 0;
    if (impl_->obstacle_idle[i] >= s.sleep_after_steps) {
      dBodySetLinearVel(b, 0, 0, 0);
      dBodySetAngularVel(b, 0, 0, 0);
      dBodyDisable(b);
      impl_->obstacle_idle[i] = 0;
    }
  }
}

void World::place_ball(const Eigen::Vector3d& p, const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  dBodySetPosition(impl_->ball, p.x(), p.y(), p.z());
  dBodySetLinearVel(impl_->ball, v.x(), v.y(), v.z());
  dBodySetAngularVel(impl_->ball, w.x(), w.y(), w.z());
  dBodySetForce(impl_->ball, 0, 0, 0);
  dBodySetTorque(impl_->ball, 0, 0, 0);
}

void World::place_obstacle(std::size_t index, double x_m, double y_m) {
  CANHIL_DEMAND(index < impl_->obstacle_geoms.size(), "no such obstacle");
  if (dBodyID b = impl_->obstacle_bodies[index]) {
    const dReal* p = dBodyGetPosition(b);
    dBodySetPosition(b, x_m, y_m, p[2]);
    dBodySetLinearVel(b, 0, 0, 0);
    dBodySetAngularVel(b, 0, 0, 0);
    dBodyEnable(b);
    impl_->obstacle_idle[index] = 0;
    impl_->canon_of(b).capture();
  } else {
    const dReal* p = dGeomGetPosition(impl_->obstacle_geoms[index]);
    dGeomSetPosition(impl_->obstacle_geoms[index], x_m, y_m, p[2]);
  }
}

WorldState World::save() const {
  WorldState s;
  s.time_s = impl_->time;
  s.seed = impl_->seed;
  s.ball = read_body(impl_->canon_of(impl_->ball));
  for (std::size_t i = 0; i < impl_->robots.size(); ++i) {
    const RobotImpl& r = impl_->robot(i);
    RobotState rs = r.state;
    rs.chassis = read_body(impl_->canon_of(r.chassis));
    for (std::size_t n = 0; n < 3; ++n) rs.wheels[n] = read_body(impl_->canon_of(r.wheel[n]));
    s.robots.push_back(rs);
  }
  for (std::size_t i = 0; i < impl_->obstacle_geoms.size(); ++i) {
    if (dBodyID b = impl_->obstacle_bodies[i]) {
      s.obstacles.push_back(read_body(impl_->canon_of(b)));
    } else {
      BodyState st;
      const dReal* p = dGeomGetPosition(impl_->obstacle_geoms[i]);
      st.position = {p[0], p[1], p[2]};
      s.obstacles.push_back(st);
    }
  }
  s.obstacle_idle_steps = impl_->obstacle_idle;
  return s;
}

void World::restore(const WorldState& s) {
  if (s.robots.size() != impl_->robots.size() || s.obstacles.size() != impl_->obstacle_geoms.size() ||
      s.obstacle_idle_steps.size() != impl_->obstacle_geoms.size()) {
    throw SetupError("the saved state has " + std::to_string(s.robots.size()) + " robots and " +
                     std::to_string(s.obstacles.size()) + " obstacles; this world has " +
                     std::to_string(impl_->robots.size()) + " and " + std::to_string(impl_->obstacle_geoms.size()));
  }
  impl_->time = s.time_s;
  impl_->seed = s.seed;
  write_body(impl_->canon_of(impl_->ball), s.ball);
  for (std::size_t i = 0; i < s.robots.size(); ++i) {
    RobotImpl& r = impl_->robot(i);
    r.state = s.robots[i];
    write_body(impl_->canon_of(r.chassis), s.robots[i].chassis);
    for (std::size_t n = 0; n < 3; ++n) write_body(impl_->canon_of(r.wheel[n]), s.robots[i].wheels[n]);
  }
  for (std::size_t i = 0; i < s.obstacles.size(); ++i) {
    if (dBodyID b = impl_->obstacle_bodies[i]) {
      write_body(impl_->canon_of(b), s.obstacles[i]);
    } else {  // a static obstacle moves only by hand (place_obstacle)
      const auto& p = s.obstacles[i].position;
      dGeomSetPosition(impl_->obstacle_geoms[i], p[0], p[1], p[2]);
    }
  }
  impl_->obstacle_idle = s.obstacle_idle_steps;
}

}  // namespace canhil::physics
