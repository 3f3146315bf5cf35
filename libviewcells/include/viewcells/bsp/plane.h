#pragma once
/// Split planes of the view space BSP (view-cell-construction paper, sections 3.4 and 4.2).
/// Axis-aligned planes compare one coordinate, which is exact in double. Geometry-aligned
/// planes are kept as the three scene points that define them, and the side of a point is
/// decided by CGAL's exact orientation predicate: the sign that decides topology never
/// depends on rounding.
#include <array>

#include "viewcells/core/vec3.h"

namespace viewcells {

struct Plane {
  Vec3 normal;      ///< unit normal; the positive side is where it points
  double offset = 0;  ///< normal . x == offset on the plane
  int axis = -1;      ///< 0, 1, 2 for axis-aligned planes (normal = +e_axis), -1 otherwise
  std::array<Vec3, 3> points{};  ///< geometry-aligned: the defining points (counter-clockwise)

  /// The plane x[axis] == value, positive side towards +axis.
  static Plane axis_aligned(int axis, double value);
  /// The plane through a, b, c; positive side where (b-a)x(c-a) points. Precondition: a, b,
  /// c not collinear.
  static Plane through(const Vec3& a, const Vec3& b, const Vec3& c);

  bool is_axis_aligned() const { return axis >= 0; }
  /// -1, 0 or +1: the exact side of p (0 only when p lies exactly on the plane).
  int side(const Vec3& p) const {
    if (axis >= 0) return p[axis] > offset ? 1 : (p[axis] < offset ? -1 : 0);
    return side_of_geometry_plane(p);
  }
  /// normal . p - offset (rounded; for interpolation and volumes, never for topology).
  double distance(const Vec3& p) const { return dot(normal, p) - offset; }

 private:
  int side_of_geometry_plane(const Vec3& p) const;  ///< CGAL's exact orientation
};

}  // namespace viewcells
