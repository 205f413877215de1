// canhil/physics/svg_plot.hpp — small, dependency-free SVG line plots of
// Plots (the experiments', and any command's: canhil timing, canhil match
// --report).
#pragma once

#include <string>
#include <vector>

#include "canhil/physics/experiments.hpp"

namespace canhil::physics {

/// One SVG document with the plots stacked vertically (axes, ticks, legend).
std::string svg_plots(const std::vector<Plot>& plots);

}  // namespace canhil::physics
