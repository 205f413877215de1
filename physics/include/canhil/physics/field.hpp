// canhil/physics/field.hpp — the field's line markings as geometry.
//
// World frame: origin at the centre spot, +x towards the goal at x = +L/2
// (the opponent's), +y to the left of it, +z up. Lines are described by their
// centrelines; each is `line_width_m` wide. Pure: no physics engine.
#pragma once

#include <vector>

#include "canhil/physics/params.hpp"

namespace canhil::physics {

struct LineSegment {
  double x0_m, y0_m, x1_m, y1_m;
};

/// An arc from start_rad to end_rad, counter-clockwise, about (cx, cy).
struct LineArc {
  double cx_m, cy_m, radius_m, start_rad, end_rad;
};

struct FieldMarkings {
  std::vector<LineSegment> segments;  ///< outer lines, halfway line, goal and penalty areas
  std::vector<LineArc> arcs;          ///< centre circle, corner arcs
  std::vector<LineArc> spots;         ///< centre and penalty marks (small full circles)
  double line_width_m = 0;

  /// Distance from (x, y) to the nearest centreline (0 on a line's centre).
  double distance_to_nearest(double x_m, double y_m) const noexcept;
};

FieldMarkings field_markings(const FieldParams& field);

}  // namespace canhil::physics
