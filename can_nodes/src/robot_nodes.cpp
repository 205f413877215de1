#include "canhil/can_nodes/robot_nodes.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace canhil::can_nodes {

RobotNodes::RobotNodes(const std::shared_ptr<const frames::MessageSet>& set, const NodeParams& params, RobotIo& robot,
                       const EndpointFactory& endpoints, Nanos start, NodeSet emulate)
    : schedule_(*set, params.ftt), start_(start), emulated_(emulate) {
  for (std::size_t i = 0; i < kNodeCount; ++i) {
    const auto id = static_cast<NodeId>(i);
    if (emulates(id)) buses_[i] = endpoints(node_name(id));
  }
  auto bus = [&](NodeId id) -> Endpoint& { return *buses_[static_cast<std::size_t>(id)]; };
  auto make = [&](NodeId id, auto build) {
    if (emulates(id)) nodes_[static_cast<std::size_t>(id)] = build(bus(id));
  };
  make(NodeId::kMaster, [&](Endpoint& b) { return std::make_unique<FttMaster>(b, set, schedule_, start); });
  make(NodeId::kPicBase, [&](Endpoint& b) { return std::make_unique<PicBase>(b, set, params, robot); });
  for (int w = 0; w < 3; ++w) {
    make(motor_node(w), [&](Endpoint& b) { return std::make_unique<MotorNode>(b, set, params, robot, w, start); });
  }
  make(NodeId::kPicOdom, [&](Endpoint& b) { return std::make_unique<PicOdom>(b, set, params); });
  make(NodeId::kCompass, [&](Endpoint& b) { return std::make_unique<CompassNode>(b, set, params, robot); });
  if (!emulates(NodeId::kSysMon)) return;
  watch_bus_ = endpoints("SysMon watch");
  auto* base = static_cast<PicBase*>(nodes_[static_cast<std::size_t>(NodeId::kPicBase)].get());
  nodes_[static_cast<std::size_t>(NodeId::kSysMon)] = std::make_unique<SystemMonitor>(
      bus(NodeId::kSysMon), set, params,
      [this] {  // the other emulated nodes' bad frames; it adds its own
        std::uint64_t n = 0;
        for (std::size_t i = 0; i < kNodeCount; ++i) {
          if (nodes_[i] && static_cast<NodeId>(i) != NodeId::kSysMon) n += nodes_[i]->counters().bad_frames();
        }
        return n;
      },
      [this, base](Nanos now) {
        // bit0: Pic_base braking (no M6); bit1: some node switched off. (A real
        // Pic_base's brake is its own to report.)
        std::uint8_t state = base != nullptr && base->watchdog_tripped(now) ? 1 : 0;
        for (const auto& n : nodes_) {
          if (n && !n->enabled()) state |= 2;
        }
        return state;
      },
      watch_bus_.get());
}

Node& RobotNodes::node(NodeId id) { return const_cast<Node&>(static_cast<const RobotNodes&>(*this).node(id)); }

const Node& RobotNodes::node(NodeId id) const {
  const auto& n = nodes_[static_cast<std::size_t>(id)];
  if (!n) throw std::logic_error(std::string(node_name(id)) + " is a real board here: canhil does not emulate it");
  return *n;
}

std::vector<Node*> RobotNodes::nodes() {
  std::vector<Node*> out;
  for (auto& n : nodes_) {
    if (n) out.push_back(n.get());
  }
  return out;
}

std::uint64_t RobotNodes::bad_frames() const {
  std::uint64_t n = 0;
  for (const auto& node : nodes_) {
    if (node) n += node->counters().bad_frames();
  }
  return n;
}

BusReport RobotNodes::bus_report() const {
  BusReport r;
  r.fewest_triggers = ~0ULL;
  if (watch_bus_) {
    const BusStats watch = watch_bus_->stats();
    r.monitor_heard = watch.received;
    r.monitor_overflow = watch.rx_overflow;
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (!nodes_[i]) continue;
    const Node& n = *nodes_[i];
    const NodeCounters& c = n.counters();
    const BusStats s = n.bus().stats();
    r.sent += c.sent;
    r.unknown_id += c.unknown_id;
    r.wrong_length += c.wrong_length;
    r.out_of_range += c.out_of_range;
    const auto id = static_cast<NodeId>(i);
    r.other_overflow += s.rx_overflow;  // the monitor's own endpoint takes only TMs
    if (id == NodeId::kSysMon) {
      r.monitor_sent = c.sent;
      r.monitor_triggers = c.triggers;
    }
    if (id == NodeId::kMaster) {
      r.tms_sent = c.sent;
      const std::uint64_t ecs = static_cast<const FttMaster&>(n).ec_count();
      r.ecs_skipped = ecs - std::min(ecs, c.sent + c.fault_dropped);
    } else if (id != NodeId::kSysMon && c.triggers < r.fewest_triggers) {
      r.fewest_triggers = c.triggers;
      r.fewest_node = node_name(id);
    }
  }
  if (r.fewest_triggers == ~0ULL) r.fewest_triggers = 0;  // no synchronous node emulated
  return r;
}

std::string describe(const BusReport& r) {
  char line[400];
  std::snprintf(line, sizeof line,
                "nodes sent %llu frames (SysMon %llu); SysMon heard %llu (%llu lost to overflow, %llu in other nodes); "
                "bad: %llu "
                "unknown id, %llu wrong length, %llu out of range; TMs: %llu sent, fewest handled %llu (%s), SysMon "
                "%llu, %llu ECs skipped",
                static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.monitor_sent),
                static_cast<unsigned long long>(r.monitor_heard), static_cast<unsigned long long>(r.monitor_overflow),
                static_cast<unsigned long long>(r.other_overflow), static_cast<unsigned long long>(r.unknown_id),
                static_cast<unsigned long long>(r.wrong_length), static_cast<unsigned long long>(r.out_of_range),
                static_cast<unsigned long long>(r.tms_sent), static_cast<unsigned long long>(r.fewest_triggers),
                r.fewest_node, static_cast<unsigned long long>(r.monitor_triggers),
                static_cast<unsigned long long>(r.ecs_skipped));
  return line;
}

void RobotNodes::set_fault_hook(FaultHook* hook) {
  for (auto& n : nodes_) {
    if (n) n->set_fault_hook(hook);
  }
}

}  // namespace canhil::can_nodes
