// canhil/can_nodes/node_ids.hpp — a robot's nodes and their names, in one
// table: the names the nodes go by on the bus, in reports, fault rules (with
// spaces written as underscores: FTT_master) and summaries; and a set of
// nodes (which of them canhil emulates on a bench shared with real boards).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

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

/// The node a name stands for: a name of kNodeNames, any case, with
/// underscores for spaces ("FTT_master", "pic_base"). None: no such node.
std::optional<NodeId> node_by_name(std::string_view name) noexcept;
/// Every node's name as a configuration writes it: "FTT_master, Pic_base, ...".
std::string node_name_list();

/// Some of a robot's nodes.
class NodeSet {
 public:
  constexpr NodeSet() noexcept = default;  ///< none
  static constexpr NodeSet all() noexcept { return NodeSet(kAll); }
  constexpr bool contains(NodeId id) const noexcept { return (bits_ & bit(id)) != 0; }
  constexpr void insert(NodeId id) noexcept { bits_ = static_cast<std::uint8_t>(bits_ | bit(id)); }
  constexpr bool empty() const noexcept { return bits_ == 0; }
  constexpr bool is_all() const noexcept { return bits_ == kAll; }
  constexpr bool operator==(const NodeSet&) const noexcept = default;

 private:
  static constexpr std::uint8_t kAll = 0xFF;
  static_assert(kNodeCount == 8, "a NodeSet's bits hold every node");
  constexpr explicit NodeSet(std::uint8_t bits) noexcept : bits_(bits) {}
  static constexpr std::uint8_t bit(NodeId id) noexcept {
    return static_cast<std::uint8_t>(1U << static_cast<unsigned>(id));
  }
  std::uint8_t bits_ = 0;
};

/// "all eight nodes", or the names in node order ("Motor1, Motor2, Motor3").
std::string describe(NodeSet set);

}  // namespace canhil::can_nodes
