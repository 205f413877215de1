#include "convex.hpp"

#include <cmath>
#include <numbers>

#include "canhil/base/demand.hpp"

namespace canhil::physics {
namespace {

struct V3 {
  double x, y, z;
};
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// A hull from a bottom and a top ring (same count, counter-clockwise from above).
ConvexShape make_hull(std::vector<V3> bottom, std::vector<V3> top) {
  CANHIL_DEMAND(bottom.size() == top.size() && bottom.size() >= 3, "hull rings must match and have 3+ points");
  ConvexShape s;
  const auto n = static_cast<unsigned int>(bottom.size());
  V3 c{0, 0, 0};
  for (const V3& p : bottom) c = {c.x + p.x, c.y + p.y, c.z + p.z};
  for (const V3& p : top) c = {c.x + p.x, c.y + p.y, c.z + p.z};
  c = {c.x / (2 * n), c.y / (2 * n), c.z / (2 * n)};
  s.offset = {c.x, c.y, c.z};
  for (V3& p : bottom) p = sub(p, c);
  for (V3& p : top) p = sub(p, c);
  for (const V3& p : bottom) s.points.insert(s.points.end(), {p.x, p.y, p.z});
  for (const V3& p : top) s.points.insert(s.points.end(), {p.x, p.y, p.z});
  s.point_count = 2 * n;
  auto point = [&](unsigned int i) { return i < n ? bottom[i] : top[i - n]; };
  auto add_face = [&](const std::vector<unsigned int>& idx) {
    V3 normal = cross(sub(point(idx[1]), point(idx[0])), sub(point(idx[2]), point(idx[1])));
    const double len = std::sqrt(dot(normal, normal));
    CANHIL_DEMAND(len > 1e-12, "degenerate hull face");
    normal = {normal.x / len, normal.y / len, normal.z / len};
    s.planes.insert(s.planes.end(), {normal.x, normal.y, normal.z, dot(normal, point(idx[0]))});
    s.polygons.push_back(static_cast<unsigned int>(idx.size()));
    s.polygons.insert(s.polygons.end(), idx.begin(), idx.end());
    ++s.plane_count;
  };
  std::vector<unsigned int> face;
  for (unsigned int i = n; i-- > 0;) face.push_back(i);  // bottom: clockwise from above
  add_face(face);
  face.clear();
  for (unsigned int i = 0; i < n; ++i) face.push_back(n + i);  // top
  add_face(face);
  for (unsigned int i = 0; i < n; ++i) {
    const unsigned int j = (i + 1) % n;
    add_face({i, j, n + j, n + i});
  }
  return s;
}

}  // namespace

ConvexShape make_prism(const Outline& outline, double z0, double z1) {
  std::vector<V3> bottom;
  std::vector<V3> top;
  for (const auto& p : outline) {
    bottom.push_back({p[0], p[1], z0});
    top.push_back({p[0], p[1], z1});
  }
  return make_hull(bottom, top);
}

ConvexShape make_frustum(double r0, double r1, double z0, double z1, int sides) {
  std::vector<V3> bottom;
  std::vector<V3> top;
  for (int i = 0; i < sides; ++i) {
    const double a = 2 * std::numbers::pi * i / sides;
    bottom.push_back({r0 * std::cos(a), r0 * std::sin(a), z0});
    top.push_back({r1 * std::cos(a), r1 * std::sin(a), z1});
  }
  return make_hull(bottom, top);
}

std::vector<Outline> notched_disc(double radius, double width, double depth) {
  constexpr double kPi = std::numbers::pi;
  const double y_back = radius - depth;  // back wall of the mouth
  const double half = width / 2;
  std::vector<Outline> pieces;
  // Back segment: the circle below y_back, closed by the chord at y_back.
  const double a0 = std::asin(y_back / radius);  // where the circle crosses y_back on the right
  Outline back;
  const int arc_points = 24;
  for (int i = 0; i <= arc_points; ++i) {
    // From the left crossing (pi - a0) round the back to the right crossing (2pi + a0).
    const double a = (kPi - a0) + (kPi + 2 * a0) * i / arc_points;
    back.push_back({radius * std::cos(a), radius * std::sin(a)});
  }
  pieces.push_back(back);
  // Horns: the circle's part beside the mouth, above y_back.
  const double a_top = std::acos(half / radius);  // circle at x = half
  const int horn_points = 6;
  Outline right{{half, y_back}};
  for (int i = 0; i <= horn_points; ++i) {
    const double a = a0 + (a_top - a0) * i / horn_points;
    right.push_back({radius * std::cos(a), radius * std::sin(a)});
  }
  pieces.push_back(right);
  Outline left;
  for (int i = 0; i <= horn_points; ++i) {
    const double a = (kPi - a_top) + (a_top - a0) * i / horn_points;
    left.push_back({radius * std::cos(a), radius * std::sin(a)});
  }
  left.push_back({-half, y_back});
  pieces.push_back(left);
  return pieces;
}

}  // namespace canhil::physics
