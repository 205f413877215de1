// app/svg_plot.hpp — small, dependency-free SVG line plots.
#pragma once

#include <string>
#include <vector>

#include "canhil/physics/experiments.hpp"

namespace canhil::app {

/// One SVG document with the plots stacked vertically (axes, ticks, legend).
std::string svg_plots(const std::vector<physics::Plot>& plots);

}  // namespace canhil::app
