#include "convex.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
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

// ---------------------------------------------------------------------------
// BoundedHull: ODE's user geom class (dCreateGeomClass) around a dConvex.

struct HullBound {
  dGeomID hull;
  double radius, z_lo, z_hi;
};

const HullBound& bound_of(dGeomID g) { return *static_cast<const HullBound*>(dGeomGetClassData(g)); }

// The bounding cylinder's box: the segment from z_lo to z_hi along the geom's
// z axis `a`, widened by the disc of `radius` about it, which reaches
// radius * sqrt(1 - a_i^2) along world axis i.
void hull_box(dGeomID g, dReal aabb[6]) {
  const HullBound& b = bound_of(g);
  const dReal* p = dGeomGetPosition(g);
  const dReal* r = dGeomGetRotation(g);  // 3x4, row-major: the z axis is column 2
  for (std::size_t i = 0; i < 3; ++i) {
    const double a = r[4 * i + 2];
    const double lo = p[i] + a * (a >= 0 ? b.z_lo : b.z_hi);
    const double hi = p[i] + a * (a >= 0 ? b.z_hi : b.z_lo);
    const double wide = b.radius * std::sqrt(std::max(0.0, 1.0 - a * a));
    aabb[2 * i] = lo - wide;
    aabb[2 * i + 1] = hi + wide;
  }
}

// Do two boxes lie apart? An infinite one (a plane's) never does.
bool apart(const dReal x[6], const dReal y[6]) {
  return x[0] > y[1] || x[1] < y[0] || x[2] > y[3] || x[3] < y[2] || x[4] > y[5] || x[5] < y[4];
}

bool infinite(const dReal box[6]) {
  return std::any_of(box, box + 6, [](dReal v) { return std::isinf(v); });
}

// ODE's own dispatch of a user class: dCollide(hull, hull) reaches it with the
// geoms swapped (a class against itself is entered as reversed), and libccd's
// contacts differ in the last bits with the order; World calls collide_hulls.
int hull_collide(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  return collide_hulls(o1, o2, flags, contact, skip);
}

dColliderFn* hull_collider(int /*other_class*/) { return &hull_collide; }

void hull_destroy(dGeomID g) { dGeomDestroy(bound_of(g).hull); }

int hull_class() {
  static const int number = [] {
    dGeomClass c{};
    c.bytes = sizeof(HullBound);
    c.collider = &hull_collider;
    c.aabb = &hull_box;
    c.aabb_test = nullptr;
    c.dtor = &hull_destroy;
    return dCreateGeomClass(&c);
  }();
  return number;
}

}  // namespace

dGeomID bounded_hull(dSpaceID space, dGeomID hull, double radius, double z_lo, double z_hi) {
  dGeomID g = dCreateGeom(hull_class());
  *static_cast<HullBound*>(dGeomGetClassData(g)) = HullBound{hull, radius, z_lo, z_hi};
  if (space != nullptr) dSpaceAdd(space, g);
  return g;
}

dGeomID hull_of(dGeomID g) { return dGeomGetClass(g) == hull_class() ? bound_of(g).hull : nullptr; }

int collide_hulls(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  dGeomID a = hull_of(o1);
  dGeomID b = hull_of(o2);
  if (a == nullptr && b == nullptr) return dCollide(o1, o2, flags, contact, skip);
  if (a == nullptr) a = o1;
  if (b == nullptr) b = o2;
  // The pairs a plain dConvex's exact box lets through, and no others: a
  // collider may find a contact a hair apart (libccd's tolerance). A hull's
  // exact box is computed here only, for the few pairs that got this far, and
  // never against a plane's infinite box (every robot's, every step).
  dReal box_a[6];
  dReal box_b[6];
  if (a == o1) {  // o1 is not a hull: its box first
    dGeomGetAABB(a, box_a);
    if (!infinite(box_a)) dGeomGetAABB(b, box_b);
    if (!infinite(box_a) && apart(box_a, box_b)) return 0;
  } else {
    dGeomGetAABB(b, box_b);
    if (!infinite(box_b)) dGeomGetAABB(a, box_a);
    if (!infinite(box_b) && apart(box_a, box_b)) return 0;
  }
  const int n = dCollide(a, b, flags, contact, skip);
  for (int i = 0; i < n; ++i) {  // the contacts name the geoms the spaces know
    auto* c = reinterpret_cast<dContactGeom*>(reinterpret_cast<char*>(contact) + static_cast<std::ptrdiff_t>(i) * skip);
    for (dGeomID* g : {&c->g1, &c->g2}) {
      if (*g == a)
        *g = o1;
      else if (*g == b)
        *g = o2;
    }
  }
  return n;
}

dGeomID ConvexShape::create(dSpaceID space, dBodyID body) {
  if (body == nullptr) {
    dGeomID g = dCreateConvex(space, planes.data(), plane_count, points.data(), point_count, polygons.data());
    dGeomSetPosition(g, offset[0], offset[1], offset[2]);
    return g;
  }
  dGeomID hull = dCreateConvex(nullptr, planes.data(), plane_count, points.data(), point_count, polygons.data());
  double radius = 0;
  double z_lo = points[2];
  double z_hi = points[2];
  for (std::size_t i = 0; i + 2 < points.size(); i += 3) {
    radius = std::max(radius, std::hypot(points[i], points[i + 1]));
    z_lo = std::min(z_lo, points[i + 2]);
    z_hi = std::max(z_hi, points[i + 2]);
  }
  dGeomID g = bounded_hull(space, hull, radius, z_lo, z_hi);
  for (dGeomID x : {hull, g}) {
    dGeomSetBody(x, body);
    dGeomSetOffsetPosition(x, offset[0], offset[1], offset[2]);
  }
  return g;
}

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
