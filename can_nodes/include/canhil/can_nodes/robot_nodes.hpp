// canhil/can_nodes/robot_nodes.hpp — one robot's emulated node set on its bus.
//
// RobotNodes builds the full set — FTT master, Pic_base, three motor nodes,
// Pic_odom, compass, system monitor — each on its own bus endpoint (a memory
// endpoint or a SocketCAN socket), so they hear each other as separate
// microcontrollers would, all reaching the robot through one RobotIo.
//
// On a bench some of those boards are real: a set may leave any node out
// (`emulate = [...]` in a scenario), the FTT master too; then the others
// answer the trigger messages of the master they hear on the bus.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <vector>

#include "canhil/can_nodes/node_ids.hpp"
#include "canhil/can_nodes/nodes.hpp"

namespace canhil::can_nodes {

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
  using EndpointFactory = std::function<std::unique_ptr<Endpoint>(const std::string& node_name)>;

  /// Builds the nodes of `emulate` (endpoints only for those; the watching
  /// one with the system monitor). `params` and `robot` must outlive it.
  /// Throws SetupError when the schedule does not fit the EC.
  RobotNodes(const std::shared_ptr<const frames::MessageSet>& set, const NodeParams& params, RobotIo& robot,
             const EndpointFactory& endpoints, Nanos start, NodeSet emulate = NodeSet::all());

  NodeSet emulated() const noexcept { return emulated_; }
  bool emulates(NodeId id) const noexcept { return emulated_.contains(id); }
  /// A node of the set; std::logic_error for one it leaves to a real board.
  Node& node(NodeId id);
  const Node& node(NodeId id) const;
  /// The emulated nodes, in NodeId order.
  std::vector<Node*> nodes();
  const frames::FttSchedule& schedule() const noexcept { return schedule_; }
  /// The time the set started at (its first EC).
  Nanos start() const noexcept { return start_; }
  PicBase& pic_base() { return static_cast<PicBase&>(node(NodeId::kPicBase)); }
  const PicBase& pic_base() const { return static_cast<const PicBase&>(node(NodeId::kPicBase)); }
  /// Bad frames counted by all emulated nodes.
  std::uint64_t bad_frames() const;
  BusReport bus_report() const;
  /// Sets the fault hook of every node (nullptr removes it).
  void set_fault_hook(FaultHook* hook);

 private:
  frames::FttSchedule schedule_;
  Nanos start_;
  NodeSet emulated_;
  std::array<std::unique_ptr<Endpoint>, kNodeCount> buses_;
  std::unique_ptr<Endpoint> watch_bus_;                  // the system monitor's second endpoint: the whole bus
  std::array<std::unique_ptr<Node>, kNodeCount> nodes_;  // NodeId order; null: a real board's
};

}  // namespace canhil::can_nodes
