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
  dGeomID create(dSpaceID space, dBodyID body = nullptr) {
    dGeomID g = dCreateConvex(space, planes.data(), plane_count, points.data(), point_count, polygons.data());
    if (body != nullptr) {
      dGeomSetBody(g, body);
      dGeomSetOffsetPosition(g, offset[0], offset[1], offset[2]);
    } else {
      dGeomSetPosition(g, offset[0], offset[1], offset[2]);
    }
    return g;
  }
};

/// A prism between z0 and z1 over `outline`.
ConvexShape make_prism(const Outline& outline, double z0, double z1);
/// A frustum (bottom radius r0 at z0, top radius r1 at z1) as an n-sided prism-like hull.
ConvexShape make_frustum(double r0, double r1, double z0, double z1, int sides);
/// A disc of `radius` with a rectangular cut-out at the front (+y), `width` wide
/// and `depth` deep, as convex pieces: the back segment and the two horns.
std::vector<Outline> notched_disc(double radius, double width, double depth);

}  // namespace canhil::physics
