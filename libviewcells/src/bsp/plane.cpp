// The one translation unit that includes CGAL (its headers are slow to compile).
#include "viewcells/bsp/plane.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "viewcells/core/error.h"

namespace viewcells {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
Kernel::Point_3 to_cgal(const Vec3& v) { return {v.x, v.y, v.z}; }
}  // namespace

Plane Plane::axis_aligned(int axis, double value) {
  VC_CHECK(axis >= 0 && axis < 3);
  Plane p;
  p.axis = axis;
  p.normal[axis] = 1.0;
  p.offset = value;
  return p;
}

Plane Plane::through(const Vec3& a, const Vec3& b, const Vec3& c) {
  Plane p;
  const Vec3 n = cross(b - a, c - a);
  const double len = length(n);
  VC_CHECK(len > 0);
  p.normal = n / len;
  // Offset from the centroid: better conditioned than from any single vertex.
  p.offset = dot(p.normal, (a + b + c) / 3.0);
  p.points = {a, b, c};
  return p;
}

int Plane::side_of_geometry_plane(const Vec3& p) const {
  switch (CGAL::orientation(to_cgal(points[0]), to_cgal(points[1]), to_cgal(points[2]), to_cgal(p))) {
    case CGAL::POSITIVE: return 1;
    case CGAL::NEGATIVE: return -1;
    default: return 0;
  }
}

}  // namespace viewcells
