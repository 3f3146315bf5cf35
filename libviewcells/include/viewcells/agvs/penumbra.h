#pragma once
/// Penumbra shadow volumes for dynamic scene edits (adaptive-global-visibility-sampling
/// paper, section 6): when an object O is inserted, every object of a view cell's PVS that
/// O may now hide, even partly, lies in O's penumbra from that cell,
///   P = { o + t (o - x) : o in O, x in the cell, t >= 0 }.
/// For convex O and cell, P is convex (a convex combination of two of its points is again of
/// that form), and its part within distance D of O is exactly the convex hull of O's
/// vertices and the points o_i + b (o_i - x_j), b = D / dist(O, cell): the hull of the
/// levels t = 0 and t = b contains every level in between. The hull is computed by CGAL from
/// the vertices of O's hull (a superset of a non-convex object) and the corners of the
/// cell's bounding box (a superset of the cell), so the region is conservative: it holds at
/// least every point O may hide from the cell.
#include <span>
#include <vector>

#include "viewcells/core/vec3.h"

namespace viewcells {

class ConvexRegion {
 public:
  /// Everything (used when the occluder touches the cell: it may hide anything from it).
  static ConvexRegion everything();
  /// The convex hull of `points` (at least 4, not coplanar; otherwise their bounding box).
  static ConvexRegion hull(std::span<const Vec3> points);
  /// Whether the box may intersect the region (conservative: true when it does, and also
  /// for some boxes near its edges).
  bool may_intersect(const Box3& box) const;
  bool is_everything() const { return everything_; }
  size_t plane_count() const { return planes_.size(); }

 private:
  bool everything_ = false;
  Box3 bounds_;
  struct HalfSpace {
    Vec3 normal;  ///< outward
    double offset = 0;  ///< inside: normal . x <= offset (+ tolerance)
  };
  std::vector<HalfSpace> planes_;
  double tolerance_ = 0;
};

/// The vertices of the points' convex hull (the points themselves when they span no volume).
std::vector<Vec3> convex_hull_vertices(std::span<const Vec3> points);

/// The penumbra of the object with vertices `occluder` from the view cell with bounds
/// `cell`, within distance `reach` of the object (the scene's diagonal covers the scene).
ConvexRegion penumbra(std::span<const Vec3> occluder, const Box3& cell, double reach);

}  // namespace viewcells
