// world_impl.hpp — the insides of World and Robot (physics/src only), shared
// by world.cpp (building, stepping, saving and restoring the world) and
// robot.cpp (a robot's wheels, kicker, grabber, compass and battery).
#pragma once

#include <ode/ode.h>

#include <Eigen/Geometry>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <numbers>
#include <vector>

#include "canhil/physics/solver_health.hpp"
#include "canhil/physics/world.hpp"
#include "convex.hpp"
#include "islands.hpp"

namespace canhil::physics {
namespace detail {

inline constexpr double kPi = std::numbers::pi;

enum class Kind : std::uint8_t { kGround, kStatic, kBall, kChassis, kWheel, kObstacle };

/// What a geom is; stored as the geom's data pointer. `id` is the creation
/// order, used to process collision pairs in an order that does not depend on
/// the spaces' internal history.
struct Tag {
  Kind kind;
  int owner = -1;  // robot or obstacle index
  int wheel = -1;
  int id = 0;
};

// Quaternions: dBodySetQuaternion renormalises, which can change the last bit
// of a quaternion ODE itself produced (and of the rotation matrix made from
// it), and renormalising is not always idempotent. So every body's quaternion
// is, after each step, fed once through dBodySetQuaternion and that input is
// kept (Canon::q_in). Saving records the input and restoring feeds the same
// input again, so ODE's internal q and R come back bit for bit.
struct Canon {
  dBodyID body = nullptr;
  std::array<double, 4> q_in{1, 0, 0, 0};

  void capture() {
    const dReal* q = dBodyGetQuaternion(body);
    q_in = {q[0], q[1], q[2], q[3]};
    apply();
  }
  void apply() const {
    const dQuaternion q = {q_in[0], q_in[1], q_in[2], q_in[3]};
    dBodySetQuaternion(body, q);
  }
};

inline Eigen::Vector3d vec(const dReal* v) { return {v[0], v[1], v[2]}; }

inline double yaw_of(dBodyID b) {
  const dReal* r = dBodyGetRotation(b);  // row-major 3x4
  return std::atan2(r[4], r[0]);         // angle of the body's +x axis
}

}  // namespace detail

struct RobotImpl {
  World::Impl* world = nullptr;
  int index = 0;
  const RobotParams* params = nullptr;
  kinematics::OmniKinematics kinematics;
  dBodyID chassis = nullptr;
  std::array<dBodyID, 3> wheel{};
  std::array<dJointID, 3> hinge{};
  std::array<dJointFeedback, 3> feedback{};
  std::array<Eigen::Vector3d, 3> axle_body{};  // hinge axis in chassis coordinates
  dSpaceID space = nullptr;                    // this robot's geoms (no self-collision)
  std::vector<std::unique_ptr<detail::Tag>> tags;
  std::vector<ConvexShape> shapes;
  RobotState state;
  double z_body = 0;  // height of the chassis body origin

  explicit RobotImpl(const RobotParams& p) : params(&p), kinematics(p.geometry) {}
  /// yaw_of(chassis), remembered with the two entries of the rotation it was
  /// computed from (bit for bit): a step's pose is asked for several times.
  double yaw() const {
    const dReal* r = dBodyGetRotation(chassis);
    const auto r0 = std::bit_cast<std::uint64_t>(r[0]);
    const auto r4 = std::bit_cast<std::uint64_t>(r[4]);
    if (!yaw_known_ || r0 != yaw_r0_ || r4 != yaw_r4_) {
      yaw_ = detail::yaw_of(chassis);
      yaw_r0_ = r0;
      yaw_r4_ = r4;
      yaw_known_ = true;
    }
    return yaw_;
  }
  Eigen::Vector3d front() const {
    const double h = yaw() + detail::kPi / 2;
    return {std::cos(h), std::sin(h), 0};
  }
  double supply_v() const;
  /// Wheel n's axle (hinge axis) in world coordinates.
  Eigen::Vector3d axle_world(std::size_t n) const {
    const dReal* rot = dBodyGetRotation(chassis);  // row-major 3x4
    const Eigen::Vector3d& a = axle_body[n];
    return {rot[0] * a.x() + rot[1] * a.y() + rot[2] * a.z(), rot[4] * a.x() + rot[5] * a.y() + rot[6] * a.z(),
            rot[8] * a.x() + rot[9] * a.y() + rot[10] * a.z()};
  }

 private:
  mutable bool yaw_known_ = false;
  mutable std::uint64_t yaw_r0_ = 0;
  mutable std::uint64_t yaw_r4_ = 0;
  mutable double yaw_ = 0;
};

struct RobotAccess {
  static RobotImpl& impl(const Robot& r) { return *r.impl_; }
  static std::unique_ptr<Robot> make(std::unique_ptr<RobotImpl> impl) {
    return std::unique_ptr<Robot>(new Robot(std::move(impl)));
  }
};

struct World::Impl {
  WorldParams params;
  std::vector<detail::Canon> canon;  // every dynamic body, in creation order
  detail::Canon& canon_of(dBodyID b) {
    for (detail::Canon& c : canon) {
      if (c.body == b) return c;
    }
    body_index.push_back(static_cast<int>(canon.size()));
    dBodySetData(b, &body_index.back());
    canon.push_back(detail::Canon{b, {1, 0, 0, 0}});
    return canon.back();
  }
  /// A body's place in `canon` (its data pointer); -1 for the static world.
  static int index_of(dBodyID b) { return b == nullptr ? -1 : *static_cast<const int*>(dBodyGetData(b)); }
  std::deque<int> body_index;     // each body's data points at its entry (a deque: entries never move)
  Islands islands;                // this substep's, as ODE will form them
  std::vector<char> big;          // per body: in an island stepped by QuickStep
  std::vector<char> was_enabled;  // per body, across the two passes of a split step
  std::uint64_t split_substeps = 0;
  std::uint64_t contact_points = 0;  // contact joints made, over every substep
  FieldMarkings markings;
  dWorldID world = nullptr;
  dSpaceID statics = nullptr;   // ground, goals, boundary, static obstacles
  dSpaceID dynamics = nullptr;  // ball, robots (as sub-spaces), movable obstacles
  dJointGroupID contacts = nullptr;
  dBodyID ball = nullptr;
  std::vector<std::unique_ptr<Robot>> robots;
  std::vector<dBodyID> obstacle_bodies;  // nullptr for static obstacles
  std::vector<dGeomID> obstacle_geoms;
  std::vector<int> obstacle_idle;  // steps still, per obstacle
  std::vector<ConvexShape> shapes;
  std::vector<std::unique_ptr<detail::Tag>> tags;
  double time = 0;
  unsigned long seed = 1;
  bool ball_on_ground = false;
  SolverHealth solver;  // what ODE said while building and stepping this world

  explicit Impl(WorldParams p);
  ~Impl();
  void build();             // the world's bodies and geoms, from params
  void release() noexcept;  // destroys what build() made, however far it got
  detail::Tag* tag(detail::Kind k, int owner = -1, int wheel = -1) {
    tags.push_back(std::make_unique<detail::Tag>(detail::Tag{k, owner, wheel, next_tag_id++}));
    return tags.back().get();
  }
  int next_tag_id = 0;
  struct Pair {
    std::uint64_t order;  // the lower creation id, then the higher: the order contacts are made in
    dGeomID a, b;         // a has the lower id
  };
  std::vector<Pair> pairs;  // candidate pairs of the current substep
  void add_static_box(double cx, double cy, double cz, double lx, double ly, double lz) {
    dGeomID g = dCreateBox(statics, lx, ly, lz);
    dGeomSetPosition(g, cx, cy, cz);
    dGeomSetData(g, tag(detail::Kind::kStatic));
  }
  void build_field();
  void build_ball();
  void build_robot(int index, const Placement& at);
  void build_obstacle(int index, const ObstaclePlacement& o);
  void substep(double h);
  void step_split(double h);
  void collide(dGeomID a, dGeomID b);
  void apply_robot_inputs(RobotImpl& r);
  void update_robot_after(RobotImpl& r, double h);
  void apply_grabber(RobotImpl& r);
  RobotImpl& robot(std::size_t i) { return RobotAccess::impl(*robots[i]); }
  const RobotImpl& robot(std::size_t i) const { return RobotAccess::impl(*robots[i]); }
};

}  // namespace canhil::physics
