// canhil/emulator/robot_nodes.hpp — one robot's emulated node set, wired to its
// physical robot and its bus.
//
// The nodes (can_nodes/) see the robot only through RobotIo; PhysicsRobotIo is
// that interface on a physics::Robot. RobotNodes builds the full set — FTT
// master, Pic_base, three motor nodes, Pic_odom, compass, system monitor — each
// on its own bus endpoint (a memory endpoint or a SocketCAN socket), so they
// hear each other as separate microcontrollers would.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "canhil/can_nodes/nodes.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::emulator {


class PhysicsRobotIo final : public can_nodes::RobotIo {
 public:
  explicit PhysicsRobotIo(physics::Robot& robot) : robot_(robot) {}
  void set_wheel_speed(int wheel, double radps) override { robot_.set_wheel_speed(wheel, radps); }
  std::int64_t encoder_count(int wheel) const override { return robot_.encoder_count(wheel); }
  bool wheel_stalled(int wheel) const override { return robot_.wheel_stalled(wheel); }
  bool over_current(int wheel) const override { return robot_.over_current(wheel); }
  KickOutcome kick(bool low, int power) override;
  void set_grabber(int mode) override { robot_.set_grabber(mode); }
  bool ball_engaged() const override { return robot_.ball_engaged(); }
  double kicker_voltage_v() const override { return robot_.kicker_voltage_v(); }
  double compass_heading_deg() const override { return robot_.compass_heading_deg(); }
  BatteryVolts battery() const override { return robot_.battery(); }

 private:
  physics::Robot& robot_;
};

/// Node parameters that match a physical robot (its wheels and encoders).
can_nodes::NodeParams node_params_for(const physics::RobotParams& robot, const can_nodes::FttConfig& ftt = {});

/// Which nodes a set has, in a fixed order (also the order they are ticked).
enum class NodeId : std::uint8_t { kMaster, kPicBase, kMotor1, kMotor2, kMotor3, kPicOdom, kCompass, kSysMon };
inline constexpr std::size_t kNodeCount = 8;
const char* node_name(NodeId id) noexcept;

/// What one robot's nodes saw and did on their bus: the run summaries' line.
struct BusReport {
  std::uint64_t sent = 0;              ///< frames all nodes handed to the bus
  std::uint64_t monitor_sent = 0;      ///< of those, the system monitor's
  std::uint64_t monitor_heard = 0;     ///< every frame the monitor's watching endpoint read, its own too
  std::uint64_t monitor_overflow = 0;  ///< frames the watching endpoint's queue dropped
  std::uint64_t other_overflow = 0;    ///< frames the nodes' own queues dropped (the monitor's TM queue too)
  std::uint64_t unknown_id = 0, wrong_length = 0, out_of_range = 0;  ///< bad frames, all nodes
  std::uint64_t tms_sent = 0;                                        ///< by the FTT master
  std::uint64_t ecs_skipped = 0;  ///< ECs the master let pass without a TM (the emulator fell behind)
  /// TMs handled by the synchronous node (Pic_base, motors, Pic_odom, compass:
  /// each must answer every TM) that handled fewest.
  std::uint64_t fewest_triggers = 0;
  const char* fewest_node = "";
  /// TMs the system monitor handled, on its own endpoint apart from the one
  /// that watches every id (so a flood does not cost it TMs either).
  std::uint64_t monitor_triggers = 0;
};
/// One line: "nodes sent S frames (SysMon M); SysMon heard H (O lost to overflow, X in other nodes); bad: ...; TMs
/// ...".
std::string describe(const BusReport& report);

class RobotNodes {
 public:
  /// Makes one bus endpoint per node, and a second one ("SysMon watch") on
  /// which the system monitor watches the whole bus.
  using EndpointFactory = std::function<std::unique_ptr<can_nodes::Bus>(const std::string& node_name)>;

  /// Builds the set. `params` and `robot` must outlive it. Throws
  /// SetupError when the schedule does not fit the EC.
  RobotNodes(const std::shared_ptr<const frames::MessageSet>& set, const can_nodes::NodeParams& params,
             can_nodes::RobotIo& robot, const EndpointFactory& endpoints, Nanos start);

  can_nodes::Node& node(NodeId id) { return *nodes_[static_cast<std::size_t>(id)]; }
  const can_nodes::Node& node(NodeId id) const { return *nodes_[static_cast<std::size_t>(id)]; }
  std::vector<can_nodes::Node*> nodes();
  const can_nodes::FttSchedule& schedule() const noexcept { return schedule_; }
  can_nodes::PicBase& pic_base() { return static_cast<can_nodes::PicBase&>(node(NodeId::kPicBase)); }
  can_nodes::PicOdom& pic_odom() { return static_cast<can_nodes::PicOdom&>(node(NodeId::kPicOdom)); }
  can_nodes::SystemMonitor& system_monitor() { return static_cast<can_nodes::SystemMonitor&>(node(NodeId::kSysMon)); }
  /// Bad frames counted by all nodes.
  std::uint64_t bad_frames() const;
  BusReport bus_report() const;
  /// Sets the fault hook of every node (nullptr removes it).
  void set_fault_hook(can_nodes::FaultHook* hook);

 private:
  can_nodes::FttSchedule schedule_;
  std::vector<std::unique_ptr<can_nodes::Bus>> buses_;
  std::unique_ptr<can_nodes::Bus> watch_bus_;  // the system monitor's second endpoint: the whole bus
  std::vector<std::unique_ptr<can_nodes::Node>> nodes_;
};

}  // namespace canhil::emulator
