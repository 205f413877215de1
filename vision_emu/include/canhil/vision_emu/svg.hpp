// canhil/vision_emu/svg.hpp — one vision frame drawn over the field: robots,
// obstacles, ball, the seeing robot's sensor rays, detected points and the
// occlusion wedges. For `canhil experiment vision` and for looking.
#pragma once

#include <string>

#include "canhil/vision_emu/vision.hpp"

namespace canhil::vision_emu {

std::string render_svg(const Vision& vision, const Scene& scene, std::size_t robot, const VisionFrame& frame);

}  // namespace canhil::vision_emu
