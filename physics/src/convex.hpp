// physics/src/convex.hpp — convex polyhedra for ODE's dConvex geoms
// (internal to physics). ODE keeps pointers to the arrays, so a ConvexShape
// must outlive every geom made from it.
#pragma once

#include <ode/ode.h>

#include <array>
#include <vector>

namespace canhil::physics {

using Outline = std::vector<std::array<double, 2>>;  // convex, counter-clockwise (seen from +z)

struct ConvexShape {
  std::vector<dReal> planes;           // a, b, c, d per face (outward unit normal, n.p = d)
  std::vector<dReal> points;           // x, y, z per vertex
  std::vector<unsigned int> polygons;  // per face: count, then vertex indices counter-clockwise from outside
  unsigned int plane_count = 0;
  unsigned int point_count = 0;
  /// Where the hull's centroid sits in the frame the outline was given in: ODE
  /// needs the origin inside the hull, so points are stored about the centroid
  /// and the geom is placed at this offset.
  std::array<double, 3> offset{};

  /// A geom in `space`; attached to `body` at the offset when given, else placed there.
  /// A geom on a body moves every step, and ODE's own bounding box of a convex
  /// transforms every vertex each time; such a geom is a BoundedHull instead,
  /// which collides as this hull and bounds it by its cylinder (bounded_hull).
  dGeomID create(dSpaceID space, dBodyID body = nullptr);
};

/// A geom in `space` that collides exactly as `hull` (a dConvex on `body`, in
/// no space, which it owns) and whose bounding box for the spaces comes from
/// the hull's bounding cylinder about its own z axis: a few operations instead
/// of a transform per vertex. A pair the looser box lets through is tested
/// against the hull's exact box before the collider, so the pairs that collide
/// and their contacts are the same as a plain dConvex's.
/// `radius`: the farthest vertex from the z axis; `z_lo`, `z_hi`: the vertices'
/// extent along it (all in the hull's frame).
dGeomID bounded_hull(dSpaceID space, dGeomID hull, double radius, double z_lo, double z_hi);
/// The dConvex a bounded_hull collides as, or nullptr for any other geom.
dGeomID hull_of(dGeomID g);
/// dCollide, with each bounded_hull replaced by its hull and the pair's order
/// kept (ODE's dispatch of a user class against itself swaps it, and libccd's
/// contacts differ in the last bits with the order); the contacts name o1 and o2.
int collide_hulls(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip);

/// A prism between z0 and z1 over `outline`.
ConvexShape make_prism(const Outline& outline, double z0, double z1);
/// A frustum (bottom radius r0 at z0, top radius r1 at z1) as an n-sided prism-like hull.
ConvexShape make_frustum(double r0, double r1, double z0, double z1, int sides);
/// A disc of `radius` with a rectangular cut-out at the front (+y), `width` wide
/// and `depth` deep, as convex pieces: the back segment and the two horns.
std::vector<Outline> notched_disc(double radius, double width, double depth);

}  // namespace canhil::physics
