// canhil/emulator/session.hpp — one run, built from a Scenario: the world,
// one rig per robot (its RobotIo, its emulated nodes, its fault injector), the
// vision, the goal watcher, the battery drain and the world log. Each rule of
// a run is written here once; drivers move a session through time:
//
//   VirtualDriver   virtual time: lockstep, memory buses, optionally the
//                   reference handler and agent in process (virtual_driver.hpp)
//   RealtimeDriver  real time: threads, SocketCAN, absolute deadlines
//                   (realtime_driver.hpp)
//
// A driver builds the nodes (build_nodes: its bus endpoints, direct or shared
// robot I/O) and, around every physics step on the thread that steps the
// world, calls before_step() and after_step(now).
//
// What watches or changes a run (the viewer, the coach, fault commands) uses
// the one narrow surface, from any thread: snapshot() reads a consistent copy
// of the world as the last step left it; apply() queues a change that takes
// effect at the next step (world changes) or the nodes' next pass (bus
// changes), in either driver.
//
// A robot canhil moves (the referee's placements, MoveRobot, RestoreWorld)
// counts one relocation in the coach's orders (CoachPlayer::relocations) its
// team's relocation_delay_s after the step that moved it, on the nodes'
// clock: virtual time and real time alike, and the same in every run of a
// seed. The laptop link writes it into COACH_INFO, where a team's agent
// learns to find itself again (CAMBADA's changePositionSN).
//
// Vision writes each robot's VISION_INFO into its agent's RTDB through the
// LaptopLink (the team's RTDB and layout, or canhil's; set RTDB_KEY to keep
// runs on canhil's RTDB apart), ticks its PMan table, then calls the frame hook.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "canhil/base/pi_mutex.hpp"
#include "canhil/can_nodes/fault.hpp"
#include "canhil/can_nodes/robot_nodes.hpp"
#include "canhil/emulator/goal_watcher.hpp"
#include "canhil/emulator/referee_desk.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/shared_robot_io.hpp"
#include "canhil/emulator/step_timing.hpp"
#include "canhil/emulator/world_log.hpp"
#include "canhil/physics/world.hpp"
#include "canhil/vision_emu/runner.hpp"

namespace canhil::emulator {

class LaptopLink;

/// One robot's part of a run.
struct Rig {
  std::size_t index = 0;
  std::size_t team = 0;     ///< its team (Scenario::teams); also its RTDB set
  int agent = 0;            ///< its agent number within its team
  std::size_t in_team = 0;  ///< its index among its team's robots (the LaptopLink's robot number)
  std::string interface;
  std::unique_ptr<can_nodes::RobotIo> io;  ///< PhysicsRobotIo or SharedRobotIo
  SharedRobotIo* shared = nullptr;         ///< io, when the nodes run on another thread than the physics
  std::unique_ptr<can_nodes::RobotNodes> nodes;
  std::unique_ptr<can_nodes::FaultInjector> faults;  ///< always there (maybe without rules)
};

/// What a watcher (the viewer) sees of a robot beyond its pose.
struct RobotDetail {
  std::optional<kinematics::Pose> odometry;    ///< what its handler reports in the RTDB
  std::optional<kinematics::Twist> commanded;  ///< what the laptop last sent its base (M6), robot frame
  kinematics::Twist achieved;                  ///< its velocity, robot frame
};

/// A robot's bus as a driver that sees every frame measures it (VirtualDriver).
struct BusDetail {
  std::uint64_t frames = 0;
  double load = 0;  ///< 0..1, over the last whole second of bus time
  /// Per periodic message, the worst |period - nominal| in that second, ms.
  std::vector<std::pair<std::string, double>> jitter_ms;
  std::optional<double> handler_latency_ms;  ///< the reference handler's last receive -> RTDB write
};

/// One robot's vision frame as its agent received it, points in the robot's frame.
struct VisionDetail {
  std::size_t robot = 0;
  double time_s = 0;
  std::vector<Eigen::Vector2d> lines, obstacles, balls;
};

/// The world as the last step left it, for whoever watches the run.
struct WorldSnapshot {
  double time_s = 0;  ///< world time
  std::uint64_t steps = 0;
  Eigen::Vector3d ball = Eigen::Vector3d::Zero();
  Eigen::Vector3d ball_velocity = Eigen::Vector3d::Zero();
  std::vector<kinematics::Pose> robots;
  std::vector<Eigen::Vector3d> obstacles;
  std::vector<Goal> goals;
  CoachState coach;  ///< the base station's orders now
  // Filled for detailed_snapshot() (at most one step late; a plain snapshot() may carry older ones):
  std::vector<RobotDetail> detail;     ///< per robot
  std::vector<BusDetail> buses;        ///< per robot, when the driver measures them
  std::optional<VisionDetail> vision;  ///< the watched robot's last frame (watch_vision)
};

/// Changes to a running world. A moved body is a physics state change like any
/// other (a robot lifted and put down: its wheels stop, its odometry does not know).
struct MoveRobot {
  std::size_t robot = 0;
  physics::Placement to;
};
struct MoveBall {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
};
struct MoveObstacle {
  std::size_t obstacle = 0;
  double x_m = 0, y_m = 0;
};
/// A fault rule from now on (its @SECONDS, if any, counts from the run's start).
struct InjectFault {
  can_nodes::FaultRule rule;
};
/// The whole world put back into a saved state (a snapshot loaded while running).
struct RestoreWorld {
  physics::WorldState state;
};
using Change = std::variant<MoveRobot, MoveBall, MoveObstacle, InjectFault, SetCoach, RestoreWorld>;

class Session {
 public:
  /// Builds the world of the plan (from the saved state if given:
  /// SetupError when it does not fit), the fault injectors, the vision and
  /// the goal watcher; attaches to the RTDB when vision is on. No nodes yet:
  /// a driver builds them. The plan is never changed.
  explicit Session(RunPlan plan);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const RunPlan& plan() const noexcept { return plan_; }
  const Scenario& scenario() const noexcept { return scenario_; }
  const SessionOptions& options() const noexcept { return options_; }
  std::size_t robot_count() const noexcept { return rigs_.size(); }

  // --- for drivers --------------------------------------------------------------
  /// A bus endpoint for robot `robot`'s node `node` (a node name, or "SysMon watch").
  using Endpoints = std::function<std::unique_ptr<can_nodes::Endpoint>(std::size_t robot, const std::string& node)>;
  enum class IoMode : std::uint8_t {
    kDirect,  ///< nodes on the thread that steps the world (virtual time)
    kShared,  ///< nodes on another thread: SharedRobotIo hands commands and sensors across
  };
  /// Builds every robot's nodes, their clocks starting at `start` (fault rule
  /// times count from there too). SetupError when the schedule does not fit.
  void build_nodes(const Endpoints& endpoints, IoMode mode, Nanos start);
  Rig& rig(std::size_t robot) { return rigs_.at(robot); }
  const Rig& rig(std::size_t robot) const { return rigs_.at(robot); }
  /// The world, for the thread that steps it.
  physics::World& world() noexcept { return *world_; }
  const physics::World& world() const noexcept { return *world_; }
  /// The parameters the nodes were built with (build_nodes).
  const can_nodes::NodeParams& node_params() const noexcept { return node_params_; }
  /// The physics step period.
  Nanos step_period() const noexcept { return step_period_; }
  /// What the world's steps and the vision cost so far, with
  /// SessionOptions::time_steps (else nothing counted).
  const StepTiming& step_timing() const noexcept { return step_timing_; }
  /// One world step at `now` on the nodes' clock, in the one order every
  /// driver uses: the queued bus changes (`with_bus_changes`: a driver whose
  /// nodes run on this thread; the real-time driver applies them on the nodes'
  /// thread each pass instead), before_step(), the physics step, after_step().
  void step(Nanos now, bool with_bus_changes = true);
  /// Before a step: the queued world changes (and, with shared I/O, the nodes' commands).
  void before_step();
  /// After a step at `now` on the nodes' clock: battery drain, vision, goals,
  /// world log, the snapshot.
  void after_step(Nanos now);
  /// On the nodes' thread, each pass: the queued bus changes (fault rules).
  void apply_bus_changes();
  /// From now on, error-frame faults are refused with this reason (a driver
  /// on CAN hardware, which no software can make send an error frame).
  void refuse_error_frames(std::string why);
  /// Throws SetupError when `rule` acts on the wire and this run has none in virtual time.
  void check_wire_rule(const can_nodes::FaultRule& rule) const;
  /// `f(link)` for every team's laptop link, in the teams' order (none without vision).
  template <class F>
  void for_each_laptop(F f) {
    for (const auto& link : laptops_) f(*link);
  }
  /// The seam to the team's laptop software (RTDB, layout, PMan, coach,
  /// replicator), or nullptr without vision.
  /// A team's laptop link (the first team's by default), or nullptr without vision.
  LaptopLink* laptop(std::size_t team = 0) noexcept { return team < laptops_.size() ? laptops_[team].get() : nullptr; }
  const LaptopLink* laptop(std::size_t team = 0) const noexcept {
    return team < laptops_.size() ? laptops_[team].get() : nullptr;
  }
  /// A team's coach orders as its laptop link writes them: its game state, its robots' players.
  CoachState team_coach(std::size_t team) const;
  /// Called after robot r's VISION_INFO is written (wake its agent).
  void on_vision_frame(std::function<void(std::size_t robot, Nanos now)> hook) { frame_hook_ = std::move(hook); }
  /// The driver's part of a detailed snapshot (its bus measurements), called
  /// on the stepping thread when a watcher asked for details.
  void on_detail(std::function<void(WorldSnapshot&)> hook) { detail_hook_ = std::move(hook); }
  /// Called with a fault rule injected while the run goes on that acts on
  /// the wire (can_nodes::wire_only, or `error` on a timed wire), for the
  /// driver whose buses have the wire; nullptr stops it.
  void on_wire_fault(std::function<void(const can_nodes::FaultRule&)> hook) { wire_fault_hook_ = std::move(hook); }
  /// Called on the stepping thread at the end of every step, after the
  /// referee (a match's tally reads the world there).
  void on_step(std::function<void(Nanos now)> hook) { step_hook_ = std::move(hook); }
  /// While the world is not stepping (paused): applies the queued changes,
  /// answers state requests and publishes the snapshot, as a step would.
  void settle();

  // --- the narrow surface (any thread) ----------------------------------------
  WorldSnapshot snapshot() const;
  /// The same with the details (odometry, commanded and achieved velocity,
  /// buses, vision) filled at the next step: one step late, and only worked
  /// out while someone asks, so a run nobody watches pays nothing.
  WorldSnapshot detailed_snapshot() const;
  /// Puts robot `robot`'s vision frames into the detailed snapshot (nullopt:
  /// none). SetupError for an unknown robot or a run without vision.
  void watch_vision(std::optional<std::size_t> robot);
  /// The whole world's state (physics::World::save) as the next step (or
  /// settle()) finds it; nullopt when the run does not get there within `wait`.
  std::optional<physics::WorldState> saved_state(std::chrono::milliseconds wait) const;
  /// Queues a change for the next step; SetupError for an unknown robot or
  /// obstacle, a fault rule whose target does not exist, a game state canhil
  /// does not know, or too many changes waiting (kMaxPendingChanges: a flood
  /// of requests cannot grow memory).
  void apply(Change change);
  static constexpr std::size_t kMaxPendingChanges = 1024;
  /// The coach's orders now (the stepping thread, or after the run).
  const CoachState& coach() const noexcept { return coach_; }
  /// Called on the stepping thread whenever the coach's orders changed (a writer puts them in the RTDB).
  void on_coach_change(std::function<void(const CoachState&)> hook) { coach_hook_ = std::move(hook); }

  // --- results (after the run, or from the stepping thread) -------------------
  /// The goals scored (a ball into a goal before a referee's restart was taken is none).
  const std::vector<Goal>& goals() const noexcept { return goals_.goals(); }
  /// The referee, when the scenario's is on (its score and calls), else nullptr.
  const Referee* referee() const noexcept { return referee_ ? &referee_->referee() : nullptr; }
  /// Called at each referee call, on the stepping thread (for the run's log).
  void on_referee_call(std::function<void(const RefereeCall&)> hook) { referee_hook_ = std::move(hook); }
  /// How many times the referee has put robot r somewhere (a kick-off's
  /// places, a step back from a restart's spot): a robot carried, not driven,
  /// whose odometry no longer knows where it is. Read on the stepping thread.
  std::uint32_t referee_placements(std::size_t r) const { return referee_ ? referee_->placements(r) : 0; }
  /// What each fault rule did, summed over the robots.
  std::vector<can_nodes::FaultCount> fault_counts() const;
  /// The world log (CSV with a header line; with a referee, its calls as
  /// "#referee,..." lines among the rows); empty when world_log_period is 0.
  const std::string& world_log() const noexcept { return world_log_ ? world_log_->text() : no_world_log_; }

 private:
  void log_world(Nanos now);
  void publish(std::uint64_t step);
  void apply_now(const Change& change);
  void apply_world_changes();
  void serve_state_requests();

  const RunPlan plan_;
  const Scenario& scenario_;       // plan_'s
  const SessionOptions& options_;  // plan_'s
  std::unique_ptr<physics::World> world_;
  Nanos step_period_{0};
  StepTiming step_timing_;
  can_nodes::NodeParams node_params_;  // the nodes keep a reference: it lives as long as they do
  std::vector<Rig> rigs_;
  std::unique_ptr<vision_emu::VisionRunner> vision_;
  std::function<void(std::size_t, Nanos)> frame_hook_;
  GoalWatcher goals_;
  std::unique_ptr<RefereeDesk> referee_;  // when the scenario's referee is on
  void referee_step(Nanos now, std::optional<bool> goal_positive_x);
  // Relocations (CoachPlayer::relocations): each one due to be counted, with its robot.
  std::vector<Nanos> relocation_delay_;                         // per team
  std::vector<std::pair<Nanos, std::size_t>> relocations_due_;  // (when, robot)
  std::vector<std::size_t> moved_;              // MoveRobot / RestoreWorld since the last step, once each
  std::vector<std::uint32_t> placements_seen_;  // per robot: the referee's, relocations already due for
  void mark_moved(std::size_t robot);
  void relocate_later(std::size_t robot, Nanos now);
  void count_relocations(Nanos now);
  void set_team_states(std::vector<std::string> states);
  CoachState coach_;
  std::function<void(const CoachState&)> coach_hook_;
  std::function<void(const RefereeCall&)> referee_hook_;
  std::function<void(WorldSnapshot&)> detail_hook_;
  std::function<void(Nanos)> step_hook_;
  // With vision, per team: its RTDB set, layout, PMan, coach, replicator.
  std::vector<std::unique_ptr<LaptopLink>> laptops_;
  std::vector<CoachState> team_coaches_;  // team_coach(t), kept with coach_
  void write_coaches();
  std::optional<WorldLogWriter> world_log_;  // with a world log period
  std::string no_world_log_;
  std::function<void(const can_nodes::FaultRule&)> wire_fault_hook_;
  std::string error_frames_refused_;  // empty: allowed
  std::uint64_t steps_ = 0;
  Nanos now_{0};  // the time of the step in progress (the vision's frame time)

  mutable PiMutex snapshot_mutex_;  // PiMutex: shared with a real-time run's node thread
  WorldSnapshot snapshot_;
  mutable std::atomic<bool> detail_asked_{false};
  std::atomic<std::size_t> vision_watched_{kNoRobot};  // kNoRobot: none
  static constexpr std::size_t kNoRobot = static_cast<std::size_t>(-1);
  std::optional<VisionDetail> vision_seen_;  // the stepping thread's copy
  struct StateRequests;
  std::unique_ptr<StateRequests> state_requests_;
  PiMutex changes_mutex_;
  std::vector<Change> world_changes_, bus_changes_;
  std::atomic<bool> any_world_change_{false}, any_bus_change_{false};  // set under the mutex; read first without it
};

}  // namespace canhil::emulator
