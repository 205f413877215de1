// canhil/emulator/virtual_run.hpp — the whole loop in virtual time, in one
// process, deterministically: the physics world; per robot its emulated nodes
// on its own in-memory bus, the reference handler (laptop::HwComm) on that bus
// and its agent's RTDB, the emulated vision writing VISION_INFO, and the
// reference agent woken after each vision frame. Every bus is recorded as a
// candump log. `canhil run --virtual-time` is built on this.
//
// Faults (can_nodes/fault.hpp) act on the frames the emulated nodes send, one
// seeded injector per robot. The world log is CSV: time, the ball, and per
// robot its true pose next to the pose its handler reports (CMD_POS).
//
// Uses the RTDB of every agent (DB_init_all; set RTDB_KEY to keep runs apart).
// Robot i is agent i + 1 (CAMBADA_1, ...) unless `agents` says otherwise.
// One VirtualRun per process at a time.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/emulator/lockstep.hpp"
#include "canhil/emulator/robot_nodes.hpp"
#include "canhil/physics/world.hpp"
#include "canhil/vision_emu/vision.hpp"

namespace canhil::emulator {

struct VirtualRunConfig {
  physics::WorldParams world;  ///< robots from its placements (at most 6)
  vision_emu::VisionParams vision;
  can_nodes::FttConfig ftt;
  std::shared_ptr<const frames::MessageSet> messages;
  int kick_power = 40;
  std::vector<std::string> interfaces;  ///< per robot, names its bus in the trace; default vcan0, vcan1, ...
  std::vector<int> agents;              ///< per robot, 1..6, all different; default 1, 2, ...
  std::vector<can_nodes::FaultRule> faults;
  std::uint64_t seed = 1;     ///< fault draws (robot r uses seed + r)
  Nanos world_log_period{0};  ///< 0: no world log
  bool record_trace = true;   ///< false: frames are counted, not kept (trace() is then empty)
  /// A saved world (physics::load_state) to start from instead of the
  /// placements; each handler's odometry is set to its robot's restored pose.
  std::optional<physics::WorldState> initial_state;
};

struct RobotOutcome {
  kinematics::Pose pose;
  int kicks = 0;             ///< kicks the agent asked for
  std::uint64_t frames = 0;  ///< on its bus
  std::uint64_t bad_frames = 0;
  BatteryVolts battery;  ///< the packs' voltages at the end
  std::array<double, 3> charge{};   ///< their state of charge, 0..1
};

/// The ball entered a goal: wholly past the goal line, between the posts, under the bar.
struct Goal {
  Nanos time{0};
  bool positive_x = true;  ///< the goal at +x (the one the reference agents attack)
};

/// Counts the ball's entries into either goal, step by step (real or virtual time).
class GoalWatcher {
 public:
  explicit GoalWatcher(const physics::WorldParams& world) : params_(world) {}
  void step(const physics::World& world, Nanos now);
  const std::vector<Goal>& goals() const noexcept { return goals_; }

 private:
  physics::WorldParams params_;
  std::vector<Goal> goals_;
  bool in_ = false;
};

class VirtualRun {
 public:
  /// Builds everything and attaches to the RTDB (DB_init_all). Throws
  /// std::invalid_argument (world, more than 6 robots) or SetupError (RTDB, schedule).
  explicit VirtualRun(const VirtualRunConfig& config);
  ~VirtualRun();
  VirtualRun(const VirtualRun&) = delete;
  VirtualRun& operator=(const VirtualRun&) = delete;

  void run_for(Nanos duration);
  Nanos now() const noexcept;
  const physics::World& world() const noexcept;
  std::vector<RobotOutcome> outcomes() const;
  /// Every bus as a candump log, one interface name per robot, in time order (record_trace).
  std::string trace() const;
  /// The world log (CSV with a header line); empty when world_log_period is 0.
  const std::string& world_log() const noexcept;
  const std::vector<Goal>& goals() const noexcept;
  /// What each fault rule did, summed over the robots.
  std::vector<can_nodes::FaultCount> fault_counts() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace canhil::emulator
