#include "canhil/emulator/physics_robot_io.hpp"

namespace canhil::emulator {

can_nodes::NodeParams node_params_for(const physics::RobotParams& robot, const frames::FttConfig& ftt) {
  can_nodes::NodeParams p;
  p.ftt = ftt;
  p.geometry = robot.geometry;
  p.encoder = robot.encoder;
  return p;
}

}  // namespace canhil::emulator
