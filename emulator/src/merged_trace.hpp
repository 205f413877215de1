// The buses' recorded frames as one candump log: by time, then robot, then
// the order each bus received them (the virtual and external drivers).
#pragma once

#include <string>
#include <vector>

#include "canhil/frames/frame.hpp"

namespace canhil::emulator {

std::string merged_trace(const std::vector<std::vector<frames::TimedFrame>>& per_bus,
                         const std::vector<std::string>& interface_names);

}  // namespace canhil::emulator
