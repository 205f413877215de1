#include "canhil/physics/field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace canhil::physics {
namespace {

double distance_to_segment(const LineSegment& s, double x, double y) {
  const double dx = s.x1_m - s.x0_m;
  const double dy = s.y1_m - s.y0_m;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((x - s.x0_m) * dx + (y - s.y0_m) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(x - (s.x0_m + t * dx), y - (s.y0_m + t * dy));
}

double distance_to_arc(const LineArc& a, double x, double y) {
  const double angle = std::atan2(y - a.cy_m, x - a.cx_m);
  const double span = a.end_rad - a.start_rad;
  double rel = std::fmod(angle - a.start_rad, 2 * std::numbers::pi);
  if (rel < 0) rel += 2 * std::numbers::pi;
  if (rel <= span + 1e-12) return std::fabs(std::hypot(x - a.cx_m, y - a.cy_m) - a.radius_m);
  const double ex0 = a.cx_m + a.radius_m * std::cos(a.start_rad);
  const double ey0 = a.cy_m + a.radius_m * std::sin(a.start_rad);
  const double ex1 = a.cx_m + a.radius_m * std::cos(a.end_rad);
  const double ey1 = a.cy_m + a.radius_m * std::sin(a.end_rad);
  return std::min(std::hypot(x - ex0, y - ey0), std::hypot(x - ex1, y - ey1));
}

}  // namespace

double FieldMarkings::distance_to_nearest(double x, double y) const noexcept {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& s : segments) best = std::min(best, distance_to_segment(s, x, y));
  for (const auto& a : arcs) best = std::min(best, distance_to_arc(a, x, y));
  return best;
}

FieldMarkings field_markings(const FieldParams& f) {
  FieldMarkings m;
  m.line_width_m = f.line_width_m;
  const double hx = f.length_m / 2;
  const double hy = f.width_m / 2;
  // Outer lines and the halfway line.
  m.segments.push_back({-hx, -hy, hx, -hy});
  m.segments.push_back({hx, -hy, hx, hy});
  m.segments.push_back({hx, hy, -hx, hy});
  m.segments.push_back({-hx, hy, -hx, -hy});
  m.segments.push_back({0, -hy, 0, hy});
  // Goal and penalty areas at both ends: two sides and the front.
  for (const double side : {-1.0, 1.0}) {
    for (const auto& [depth, width] : {std::pair{f.goal_area_depth_m, f.goal_area_width_m},
                                       std::pair{f.penalty_area_depth_m, f.penalty_area_width_m}}) {
      const double x_line = side * hx;
      const double x_front = side * (hx - depth);
      m.segments.push_back({x_line, -width / 2, x_front, -width / 2});
      m.segments.push_back({x_front, -width / 2, x_front, width / 2});
      m.segments.push_back({x_front, width / 2, x_line, width / 2});
    }
  }
  const double pi = std::numbers::pi;
  m.arcs.push_back({0, 0, f.centre_circle_radius_m, 0, 2 * pi});
  if (f.corner_arc_radius_m > 0) {
    m.arcs.push_back({hx, hy, f.corner_arc_radius_m, pi, 1.5 * pi});
    m.arcs.push_back({-hx, hy, f.corner_arc_radius_m, 1.5 * pi, 2 * pi});
    m.arcs.push_back({-hx, -hy, f.corner_arc_radius_m, 0, 0.5 * pi});
    m.arcs.push_back({hx, -hy, f.corner_arc_radius_m, 0.5 * pi, pi});
  }
  const double spot = f.line_width_m / 2;
  m.spots.push_back({0, 0, spot, 0, 2 * pi});
  m.spots.push_back({hx - f.penalty_mark_distance_m, 0, spot, 0, 2 * pi});
  m.spots.push_back({-hx + f.penalty_mark_distance_m, 0, spot, 0, 2 * pi});
  return m;
}

}  // namespace canhil::physics
