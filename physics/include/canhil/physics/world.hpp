// canhil/physics/world.hpp — the ODE world: field, goals, ball, omni-wheeled
// robots and obstacles.
//
// Parameters (WorldParams) are fixed at construction; everything that moves is
// in the world's state, which save() / restore() capture completely (stepping
// from a restored state repeats the original bit for bit). step() advances one
// SimulationParams::step_s. ODE stays behind this header: nodes and vision see
// Robot's narrow interface (wheel speed, wheel angle, kick, barrier, grabber,
// heading, battery) and the World's read-only queries.
//
// Thread safety: a World and its Robots are used from one thread. Several
// Worlds may live in one process; each keeps its own copy of ODE's random seed.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "canhil/base/robot.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/kinematics/omni.hpp"
#include "canhil/physics/field.hpp"
#include "canhil/physics/params.hpp"
#include "canhil/physics/solver_health.hpp"

namespace canhil::physics {

/// One rigid body's complete dynamic state (quaternion w, x, y, z).
struct BodyState {
  std::array<double, 3> position{};
  std::array<double, 4> quaternion{1, 0, 0, 0};
  std::array<double, 3> linear_velocity{};
  std::array<double, 3> angular_velocity{};
  bool enabled = true;  ///< false while asleep (movable obstacles at rest)
  friend bool operator==(const BodyState&, const BodyState&) = default;
};

struct RobotState {
  BodyState chassis;
  std::array<BodyState, 3> wheels;
  std::array<double, 3> wheel_angle_rad{};  ///< unwrapped since start
  std::array<double, 3> hinge_angle_rad{};  ///< ODE's wrapped hinge angle at the last substep
  /// The motor controllers' target speeds (the firmware's speed loop holds them within the motor's torque).
  std::array<double, 3> wheel_target_radps{};
  std::array<double, 3> motor_current_a{};
  double kicker_voltage_v = 0;
  int grabber_mode = 0;
  double grabber_release_left_s = 0;
  double last_kick_time_s = -1;
  std::array<double, 3> charge{};  ///< state of charge of the logic, 12 V and 24 V packs
  friend bool operator==(const RobotState&, const RobotState&) = default;
};

struct WorldState {
  double time_s = 0;
  unsigned long seed = 0;
  BodyState ball;
  std::vector<RobotState> robots;
  std::vector<BodyState> obstacles;      ///< movable and static alike (static ones never change)
  std::vector<int> obstacle_idle_steps;  ///< steps each movable obstacle has been still
  friend bool operator==(const WorldState&, const WorldState&) = default;
};

/// Writes a state as text with every double in hexadecimal floating point, so
/// that reading it back is exact. Throws SetupError when the file cannot be written.
void save_state(const WorldState& state, const std::filesystem::path& path);
/// Reads what save_state wrote; throws SetupError naming the line on a malformed file.
WorldState load_state(const std::filesystem::path& path);

struct KickResult {
  KickOutcome outcome = KickOutcome::kNoPower;
  double speed_mps = 0;  ///< launch speed relative to the robot, when fired
  bool fired() const noexcept { return outcome == KickOutcome::kFired; }
};

/// The kick rule, written once: what a kick of `power` does with the barrier
/// and the capacitor in this state (Robot::kick fires by it; the real-time
/// path asks it on the state the physics published).
KickOutcome kick_outcome(const KickerParams& kicker, int power, bool ball_engaged, double kicker_voltage_v) noexcept;

class World;
struct RobotImpl;
struct RobotAccess;

/// One robot of a World: the narrow interface the emulated nodes use, plus
/// ground truth for tests and experiments. Owned by its World.
class Robot {
 public:
  // --- motors and encoders (the motor nodes) ---------------------------------
  /// Speed control of wheel n (0..2) in rad/s, positive driving the base along F_n.
  void set_wheel_speed(int wheel, double radps);
  /// All wheels held at zero speed (the firmware's brake).
  void brake();
  double wheel_angle_rad(int wheel) const;
  double wheel_speed_radps(int wheel) const;
  /// Absolute encoder count (500 ppr x4 x gear 15 per wheel turn by default), from the wheel angle.
  std::int64_t encoder_count(int wheel) const;
  double motor_current_a(int wheel) const;
  /// Commanded to turn but standing still at the current limit.
  bool wheel_stalled(int wheel) const;
  /// Motor current at the driver's limit.
  bool over_current(int wheel) const;

  // --- kick system (Pic_base) -------------------------------------------------
  /// Fires the kicker: low (direct, along the carpet) or high (lob), power
  /// 0..max_power (capped). Only while ball_engaged(); speed follows
  /// v = v_m * p / p_m * (capacitor voltage / full voltage).
  KickResult kick(bool low, int power);
  /// Grabber mode 0..100 (0 off); pulls the ball into the mouth when in range.
  void set_grabber(int mode);
  int grabber_mode() const;
  /// The barrier: the ball is in the control area.
  bool ball_engaged() const;
  double kicker_voltage_v() const;
  /// Time of the last kick that fired, or -1.
  double last_kick_time_s() const;

  // --- compass and battery ------------------------------------------------------
  /// Heading of the robot's front, clockwise from magnetic north, [0, 360).
  double compass_heading_deg() const;
  BatteryVolts battery() const;
  /// State of charge of the logic, 12 V and 24 V packs, 0..1.
  std::array<double, 3> charge() const;
  /// Takes these fractions of a full pack from each pack on top of what the
  /// robot uses (a fault: a failing cell, a drain left on); never below empty.
  void drain(const std::array<double, 3>& fraction);

  // --- ground truth ---------------------------------------------------------------
  kinematics::Pose pose() const;
  /// Velocity in the robot's own frame.
  kinematics::Twist twist() const;
  /// Moves the robot (teleport) and stops it.
  void place(const Placement& at);
  const RobotParams& params() const;

  Robot(const Robot&) = delete;
  Robot& operator=(const Robot&) = delete;
  ~Robot();

 private:
  friend struct RobotAccess;
  explicit Robot(std::unique_ptr<RobotImpl> impl);
  std::unique_ptr<RobotImpl> impl_;
};

class World {
 public:
  /// Builds the world; throws SetupError for impossible parameters.
  explicit World(WorldParams params);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const WorldParams& params() const noexcept;
  const FieldMarkings& markings() const noexcept;

  /// Advances the world by params().simulation.step_s.
  void step();
  double time_s() const noexcept;
  /// What ODE reported while this world was built and stepped (solver_health.hpp).
  /// A world whose ODE stopped threw SolverError from the constructor or step().
  const SolverHealth& solver_health() const noexcept;
  /// Substeps so far in which an island larger than
  /// simulation.exact_solver_max_rows went to QuickStep (a scrum).
  std::uint64_t large_island_substeps() const noexcept;
  /// Contact points (ODE contact joints) made so far, over every substep: what
  /// the solver's rows grow with as bodies touch (`canhil bench --part match`).
  std::uint64_t contact_points() const noexcept;

  std::size_t robot_count() const noexcept;
  Robot& robot(std::size_t index);
  const Robot& robot(std::size_t index) const;

  Eigen::Vector3d ball_position() const;
  Eigen::Vector3d ball_velocity() const;
  /// The ball touched the carpet during the last substep.
  bool ball_on_ground() const noexcept;
  void place_ball(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity = Eigen::Vector3d::Zero(),
                  const Eigen::Vector3d& spin = Eigen::Vector3d::Zero());

  std::size_t obstacle_count() const noexcept;
  Eigen::Vector3d obstacle_position(std::size_t index) const;
  const ObstacleParams& obstacle_params(std::size_t index) const;
  /// Moves obstacle `index` (< obstacle_count()) to (x, y) on the carpet and stops it.
  void place_obstacle(std::size_t index, double x_m, double y_m);

  WorldState save() const;
  /// Restores a state saved from a world with the same parameters (same robot
  /// and obstacle count); throws SetupError otherwise.
  void restore(const WorldState& state);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace canhil::physics
