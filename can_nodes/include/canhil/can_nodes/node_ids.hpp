// canhil/can_nodes/node_ids.hpp — a robot's nodes and their names, in one
// table: the names the nodes go by on the bus, in reports, fault rules (with
// spaces written as underscores: FTT_master) and summaries.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace canhil::can_nodes {

/// A robot's nodes, in a fixed order (also the order they are ticked).
enum class NodeId : std::uint8_t { kMaster, kPicBase, kMotor1, kMotor2, kMotor3, kPicOdom, kCompass, kSysMon };
inline constexpr std::size_t kNodeCount = 8;

inline constexpr std::array<const char*, kNodeCount> kNodeNames = {"FTT master", "Pic_base", "Motor1",  "Motor2",
                                                                   "Motor3",     "Pic_odom", "Compass", "SysMon"};

constexpr const char* node_name(NodeId id) noexcept { return kNodeNames[static_cast<std::size_t>(id)]; }
/// Motor node of wheel 0..2.
constexpr NodeId motor_node(int wheel) noexcept {
  return static_cast<NodeId>(static_cast<int>(NodeId::kMotor1) + wheel);
}

}  // namespace canhil::can_nodes
