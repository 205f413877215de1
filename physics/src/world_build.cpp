// World's construction (world.hpp): ODE started once, then the field and its
// goals, the ball, the robots and the obstacles made from WorldParams. Stepping,
// saving and restoring are in world.cpp.
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "canhil/base/setup_error.hpp"
#include "solver_scope.hpp"
#include "world_impl.hpp"

namespace canhil::physics {
namespace {

using detail::Kind;
using detail::Tag;

void init_ode_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    dInitODE2(0);
    detail::install_solver_handlers();
  });
}

}  // namespace

// ---------------------------------------------------------------------------
// Construction

World::Impl::Impl(WorldParams p) : params(std::move(p)), markings(field_markings(params.field)) {
  init_ode_once();
  const SimulationParams& s = params.simulation;
  if (!(s.step_s > 0) || s.substeps < 1) throw SetupError("simulation step and substeps must be positive");
  const detail::SolverScope scope(solver, time);
  try {
    build();
  } catch (...) {  // ODE stopped (SolverError): what was made so far is released
    release();
    throw;
  }
}

void World::Impl::build() {
  const SimulationParams& s = params.simulation;

  seed = s.seed;
  world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -s.gravity_mps2);
  dWorldSetCFM(world, s.cfm);
  dWorldSetERP(world, s.erp);
  dWorldSetQuickStepNumIterations(world, s.solver_iterations);
  dWorldSetContactSurfaceLayer(world, 0.0005);
  // Penetration is corrected gently so that it never adds energy to a bounce.
  dWorldSetContactMaxCorrectingVel(world, 0.2);
  dWorldSetAutoDisableFlag(world, 0);
  statics = dHashSpaceCreate(nullptr);
  dynamics = dHashSpaceCreate(nullptr);
  dHashSpaceSetLevels(dynamics, -4, 2);
  contacts = dJointGroupCreate(0);
  build_field();
  build_ball();
  for (std::size_t i = 0; i < params.robots.size(); ++i) build_robot(static_cast<int>(i), params.robots[i]);
  for (std::size_t i = 0; i < params.obstacles.size(); ++i) build_obstacle(static_cast<int>(i), params.obstacles[i]);
}

World::Impl::~Impl() { release(); }

void World::Impl::release() noexcept {
  robots.clear();
  if (contacts != nullptr) dJointGroupDestroy(contacts);
  if (dynamics != nullptr) dSpaceDestroy(dynamics);  // destroys contained geoms and sub-spaces (cleanup mode on)
  if (statics != nullptr) dSpaceDestroy(statics);
  if (world != nullptr) dWorldDestroy(world);
  contacts = nullptr;
  dynamics = statics = nullptr;
  world = nullptr;
}

void World::Impl::build_field() {
  const FieldParams& f = params.field;
  dGeomID ground = dCreatePlane(statics, 0, 0, 1, 0);
  dGeomSetData(ground, tag(Kind::kGround));
  const GoalParams& g = f.goal;
  const double hx = f.length_m / 2;
  const double t = g.post_thickness_m;
  const double net = 0.02;  // net thickness
  for (const double side : {-1.0, 1.0}) {
    const double x_post = side * (hx + t / 2);
    for (const double ys : {-1.0, 1.0})
      add_static_box(x_post, ys * (g.width_m / 2 + t / 2), g.height_m / 2, t, t, g.height_m);
    add_static_box(x_post, 0, g.height_m + t / 2, t, g.width_m + 2 * t, t);  // bar
    const double x_back = side * (hx + g.depth_m + net / 2);
    add_static_box(x_back, 0, g.height_m / 2, net, g.width_m + 2 * t, g.height_m);  // back net
    const double x_mid = side * (hx + g.depth_m / 2);
    for (const double ys : {-1.0, 1.0}) {
      add_static_box(x_mid, ys * (g.width_m / 2 + net / 2), g.height_m / 2, g.depth_m, net, g.height_m);  // side nets
    }
    add_static_box(x_mid, 0, g.height_m + net / 2, g.depth_m, g.width_m, net);  // roof net
  }
  if (f.boundary) {
    const double bx = hx + f.margin_m;
    const double by = f.width_m / 2 + f.margin_m;
    const double w = 0.1;
    const double h = f.boundary_height_m;
    add_static_box(bx + w / 2, 0, h / 2, w, 2 * by + 2 * w, h);
    add_static_box(-bx - w / 2, 0, h / 2, w, 2 * by + 2 * w, h);
    add_static_box(0, by + w / 2, h / 2, 2 * bx, w, h);
    add_static_box(0, -by - w / 2, h / 2, 2 * bx, w, h);
  }
}

void World::Impl::build_ball() {
  const BallParams& b = params.ball;
  ball = dBodyCreate(world);
  dMass m;
  // A football is a shell: I = 2/3 m r^2.
  const double inertia = 2.0 / 3.0 * b.mass_kg * b.radius_m * b.radius_m;
  dMassSetParameters(&m, b.mass_kg, 0, 0, 0, inertia, inertia, inertia, 0, 0, 0);
  dBodySetMass(ball, &m);
  dGeomID g = dCreateSphere(dynamics, b.radius_m);
  dGeomSetBody(g, ball);
  dGeomSetData(g, tag(Kind::kBall));
  dBodySetPosition(ball, params.ball_start.x_m, params.ball_start.y_m, params.ball_start.z_m);
  canon_of(ball).capture();
}

void World::Impl::build_robot(int index, const Placement& at) {
  const RobotParams& p = params.robot;
  auto impl = std::make_unique<RobotImpl>(p);
  RobotImpl& r = *impl;
  r.world = this;
  r.index = index;
  r.space = dSimpleSpaceCreate(dynamics);
  dSpaceSetCleanup(r.space, 1);

  // Chassis: the notched cylinder as three convex prisms, the camera cone as a frustum.
  r.chassis = dBodyCreate(world);
  dMass m;
  dMassSetCylinderTotal(&m, p.mass_kg, 3, p.body_radius_m, p.body_height_m);
  dBodySetMass(r.chassis, &m);
  r.z_body = p.body_clearance_m + p.body_height_m / 2;
  const double z0 = -p.body_height_m / 2;
  const double z1 = p.body_height_m / 2;
  for (auto& outline : notched_disc(p.body_radius_m, p.mouth_width_m, p.mouth_depth_m)) {
    r.shapes.push_back(make_prism(outline, z0, z1));
  }
  // The cone collides with a base radius that leaves the mouth free above the
  // ball, so a lob can leave; vision uses the full cone_radius_m.
  const double cone_base = std::min(p.cone_radius_m, p.body_radius_m - p.mouth_depth_m - 0.01);
  r.shapes.push_back(make_frustum(cone_base, std::min(p.cone_top_radius_m, cone_base), z1, z1 + p.cone_height_m, 16));
  for (auto& shape : r.shapes) {
    dGeomID g = shape.create(r.space, r.chassis);
    r.tags.push_back(std::make_unique<Tag>(Tag{Kind::kChassis, index, -1, next_tag_id++}));
    dGeomSetData(g, r.tags.back().get());
  }

  // Wheels: spheres on motorised hinges; the axle points at the centre so that
  // a positive hinge rate drives the base along F_n.
  const double wr = p.geometry.wheel_radius_m;
  for (std::size_t n = 0; n < 3; ++n) {
    const double phi = p.geometry.wheel_angles_deg[n] * detail::kPi / 180.0;
    const Eigen::Vector3d u(std::cos(phi), std::sin(phi), 0);
    r.axle_body[n] = -u;
    dBodyID w = dBodyCreate(world);
    dMass wm;
    const double iw = 2.0 / 5.0 * p.wheel_mass_kg * wr * wr;
    // The motor's rotor turns gear_ratio times faster: it adds J * gear^2 about the axle.
    const double ir = p.motor.rotor_inertia_kgm2 * p.encoder.gear_ratio * p.encoder.gear_ratio;
    const Eigen::Vector3d a = -u;
    dMassSetParameters(&wm, p.wheel_mass_kg, 0, 0, 0, iw + ir * a.x() * a.x(), iw + ir * a.y() * a.y(),
                       iw + ir * a.z() * a.z(), ir * a.x() * a.y(), ir * a.x() * a.z(), ir * a.y() * a.z());
    dBodySetMass(w, &wm);
    dGeomID g = dCreateSphere(r.space, wr);
    dGeomSetBody(g, w);
    r.tags.push_back(std::make_unique<Tag>(Tag{Kind::kWheel, index, static_cast<int>(n), next_tag_id++}));
    dGeomSetData(g, r.tags.back().get());
    r.wheel[n] = w;
    dJointID j = dJointCreateHinge(world, nullptr);
    r.hinge[n] = j;
    dJointSetFeedback(j, &r.feedback[n]);
  }
  robots.push_back(RobotAccess::make(std::move(impl)));
  robots.back()->place(at);
  RobotImpl& ri = RobotAccess::impl(*robots.back());
  ri.state.kicker_voltage_v = p.kicker.full_voltage_v;
  ri.state.charge.fill(p.battery.initial_charge);
}

void World::Impl::build_obstacle(int index, const ObstaclePlacement& o) {
  shapes.push_back(
      make_frustum(o.params.radius_m, o.params.radius_m, -o.params.height_m / 2, o.params.height_m / 2, 16));
  dBodyID body = nullptr;
  dGeomID g = nullptr;
  if (o.params.movable) {
    body = dBodyCreate(world);
    dMass m;
    dMassSetCylinderTotal(&m, o.params.mass_kg, 3, o.params.radius_m, o.params.height_m);
    dBodySetMass(body, &m);
    g = shapes.back().create(dynamics, body);
    dBodySetPosition(body, o.at.x_m, o.at.y_m, o.params.height_m / 2);
    dMatrix3 rot;
    dRFromAxisAndAngle(rot, 0, 0, 1, o.at.heading_deg * detail::kPi / 180.0);
    dBodySetRotation(body, rot);
    canon_of(body).capture();
  } else {
    g = shapes.back().create(statics);
    dGeomSetPosition(g, o.at.x_m, o.at.y_m, o.params.height_m / 2);
  }
  dGeomSetData(g, tag(Kind::kObstacle, index));
  obstacle_bodies.push_back(body);
  obstacle_geoms.push_back(g);
  obstacle_idle.push_back(0);
}

}  // namespace canhil::physics
