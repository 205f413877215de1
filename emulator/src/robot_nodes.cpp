#include "canhil/emulator/robot_nodes.hpp"

namespace canhil::emulator {

can_nodes::KickOutcome PhysicsRobotIo::kick(bool low, int power) {
  switch (robot_.kick(low, power).outcome) {
    case physics::KickResult::Outcome::kFired:
      return can_nodes::KickOutcome::kFired;
    case physics::KickResult::Outcome::kNotEngaged:
      return can_nodes::KickOutcome::kNotEngaged;
    case physics::KickResult::Outcome::kLowVoltage:
      return can_nodes::KickOutcome::kLowVoltage;
    case physics::KickResult::Outcome::kNoPower:
      return can_nodes::KickOutcome::kNoPower;
  }
  return can_nodes::KickOutcome::kNoPower;
}

can_nodes::BatteryVolts PhysicsRobotIo::battery() const {
  const physics::BatteryReading b = robot_.battery();
  return {b.logic_v, b.power12_v, b.power24_v};
}

can_nodes::NodeParams node_params_for(const physics::RobotParams& robot, const can_nodes::FttConfig& ftt) {
  can_nodes::NodeParams p;
  p.ftt = ftt;
  p.geometry = robot.geometry;
  p.encoder = robot.encoder;
  return p;
}

const char* node_name(NodeId id) noexcept {
  static constexpr const char* kNames[] = {"FTT master", "Pic_base", "Motor1",  "Motor2",
                                           "Motor3",     "Pic_odom", "Compass", "SysMon"};
  return kNames[static_cast<std::size_t>(id)];
}

RobotNodes::RobotNodes(const std::shared_ptr<const frames::MessageSet>& set, const can_nodes::NodeParams& params,
                       can_nodes::RobotIo& robot, const EndpointFactory& endpoints, Nanos start)
    : schedule_(*set, params.ftt) {
  for (std::size_t i = 0; i < kNodeCount; ++i) buses_.push_back(endpoints(node_name(static_cast<NodeId>(i))));
  auto bus = [&](NodeId id) -> can_nodes::Bus& { return *buses_[static_cast<std::size_t>(id)]; };
  nodes_.push_back(std::make_unique<can_nodes::FttMaster>(bus(NodeId::kMaster), set, schedule_, start));
  nodes_.push_back(std::make_unique<can_nodes::PicBase>(bus(NodeId::kPicBase), set, params, robot));
  for (int w = 0; w < 3; ++w) {
    nodes_.push_back(
        std::make_unique<can_nodes::MotorNode>(bus(static_cast<NodeId>(2 + w)), set, params, robot, w, start));
  }
  nodes_.push_back(std::make_unique<can_nodes::PicOdom>(bus(NodeId::kPicOdom), set, params));
  nodes_.push_back(std::make_unique<can_nodes::CompassNode>(bus(NodeId::kCompass), set, params, robot));
  auto* base = static_cast<can_nodes::PicBase*>(nodes_[1].get());
  nodes_.push_back(std::make_unique<can_nodes::SystemMonitor>(
      bus(NodeId::kSysMon), set, params, [this] { return bad_frames(); },
      [this, base](Nanos now) {
        // bit0: Pic_base braking (no M6); bit1: some node switched off.
        std::uint8_t state = base->watchdog_tripped(now) ? 1 : 0;
        for (const auto& n : nodes_) {
          if (!n->enabled()) state |= 2;
        }
        return state;
      }));
}

std::vector<can_nodes::Node*> RobotNodes::nodes() {
  std::vector<can_nodes::Node*> out;
  for (auto& n : nodes_) out.push_back(n.get());
  return out;
}

std::uint64_t RobotNodes::bad_frames() const {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i + 1 < nodes_.size(); ++i) n += nodes_[i]->counters().bad_frames();  // all but SysMon
  return n;
}

void RobotNodes::set_fault_hook(can_nodes::FaultHook* hook) {
  for (auto& n : nodes_) n->set_fault_hook(hook);
}

}  // namespace canhil::emulator
