// canhil/emulator/virtual_driver.hpp — a session in virtual time, in one
// process, deterministically: per robot its emulated nodes on its own
// in-memory bus and, optionally, the reference handler (laptop::HwComm) on
// that bus and the reference agent on its RTDB, woken after each vision frame,
// both through the team's laptop link (its RTDB, in its layout); everything
// advanced in lockstep with the physics. With the reference laptop canhil's
// RTDB stamps and ages items in the run's virtual time while the driver lives
// (LaptopLink::set_clock; a team's library keeps the wall clock). Every bus can be recorded
// as a candump log (one interface name per robot). `canhil run --virtual-time`,
// `canhil bench` and the tests (tests/support/one_robot_session.hpp) are built on this.
//
// Not thread-safe: one thread drives it (the session's snapshot() and apply()
// may be used from others).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/emulator/bus_watch.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/laptop/hwcomm.hpp"

namespace canhil::emulator {

struct VirtualOptions {
  /// The reference handler and agent per robot, in process (with their RTDB
  /// cleared at start and the handler's odometry set to the robot's pose, and
  /// set again wherever the referee carries the robot).
  bool reference_handler_and_agent = true;
  bool count_frames = true;  ///< a listener on every bus counts its frames (RobotOutcome::frames)
  bool record_trace = true;  ///< and keeps them for trace(); false: trace() is empty
  /// Every bus checked as `canhil timing` would (FTT windows, periods), in
  /// constant memory: ftt_violations().
  bool check_timing = false;
  /// The nodes a scenario leaves to real boards (Scenario::emulate) are
  /// played by the caller, who adds them on the robots' buses (add()). False:
  /// such a scenario is refused, as nothing would play those boards.
  bool caller_plays_real_boards = false;
};

struct RobotOutcome {
  kinematics::Pose pose;
  int kicks = 0;             ///< kicks the reference agent asked for
  std::uint64_t frames = 0;  ///< on its bus
  std::uint64_t bad_frames = 0;
  BatteryVolts battery;            ///< the packs' voltages at the end
  std::array<double, 3> charge{};  ///< their state of charge, 0..1
};

class VirtualDriver {
 public:
  /// Builds the buses, the nodes (their clocks start at 0) and, if asked, the
  /// reference laptop stack. `session` must outlive the driver.
  VirtualDriver(Session& session, VirtualOptions options = {});
  ~VirtualDriver();
  VirtualDriver(const VirtualDriver&) = delete;
  VirtualDriver& operator=(const VirtualDriver&) = delete;

  void run_for(Nanos duration);
  void run_until(Nanos end);
  Nanos now() const noexcept { return clock_.now(); }

  /// Robot r's bus, for what a test attaches (a laptop endpoint, a listener).
  can_nodes::MemoryBus& bus(std::size_t robot) { return *buses_.at(robot); }
  const can_nodes::MemoryBus& bus(std::size_t robot) const { return *buses_.at(robot); }
  /// Another participant (ticked after the nodes and the reference laptop),
  /// such as a node playing a real board; must outlive the driver.
  void add(can_nodes::Participant& p) { time_.add(p); }
  void add(can_nodes::Node& node) { time_.add(node); }
  const can_nodes::SimulatedClock& clock() const noexcept { return clock_; }
  std::uint64_t physics_steps() const noexcept { return time_.steps(); }

  std::vector<RobotOutcome> outcomes() const;
  /// Robot r's in-process reference handler, or nullptr without the reference laptop.
  const laptop::HwComm* handler(std::size_t robot) const;
  /// The FTT and timing violations on robot r's bus so far (check_timing; else 0).
  std::uint64_t ftt_violations(std::size_t robot) const;
  /// BusWatch::trace_hash of the frames so far (with a tap on: count_frames, record_trace or check_timing).
  std::uint64_t trace_hash() const noexcept;
  /// Every bus as a candump log, one interface name per robot, in time order (record_trace).
  std::string trace() const;

  struct ReferenceStack;  // the reference handler and agent of one robot (canhil's laptop software)

 private:
  void set_pose_of_carried_robots();
  void fill_detail(WorldSnapshot& s);
  // The rules that act on the wire, on every robot's timed bus.
  void add_wire_faults(const std::vector<can_nodes::FaultRule>& rules);

  Session& session_;
  VirtualOptions options_;
  can_nodes::SimulatedClock clock_;
  std::vector<std::unique_ptr<can_nodes::MemoryBus>> buses_;
  // On a timed wire, each robot's controllers by the name fault rules give
  // them (nodes as fault_node_name, "laptop" for the handler).
  std::vector<std::map<std::string, wire::ControllerId, std::less<>>> controllers_;
  bool listening_ = false;  // the buses' taps count, check or record their frames
  BusWatch watch_;
  std::vector<std::unique_ptr<ReferenceStack>> stacks_;
  can_nodes::VirtualTime time_;
  bool rtdb_clock_set_ = false;  // the RTDB stamps and ages items in this run's virtual time
};

}  // namespace canhil::emulator
