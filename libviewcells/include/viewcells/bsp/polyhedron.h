#pragma once
/// Convex polyhedra: the cells of the view space BSP. A boundary representation (vertices and
/// faces, each face tagged with the plane it lies on) that splits by any plane, with volume,
/// containment and segment clipping. Vertex sides are decided by Plane::side (exact), and a
/// vertex within the rounding of the plane counts as on it, so a split never makes a vertex
/// that nearly duplicates another (an edge of arbitrary direction); new vertices are computed
/// in double, and those of the plane's section closer than the rounding are welded.
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "viewcells/bsp/plane.h"
#include "viewcells/core/vec3.h"

namespace viewcells {

struct PolyFace {
  std::vector<uint32_t> vertices;  ///< counter-clockwise seen from outside
  int32_t plane = -1;              ///< id of the plane it lies on (caller's numbering)
  bool outward_positive = false;   ///< the outward normal is the plane's normal (else its negation)
};

class ConvexPolyhedron {
 public:
  ConvexPolyhedron() = default;
  /// A box; its faces get plane ids first_plane_id + (0: -x, 1: +x, 2: -y, 3: +y, 4: -z, 5: +z).
  static ConvexPolyhedron box(const Box3& b, int32_t first_plane_id);

  /// Splits by `plane` (id `plane_id` tags the new cap faces): first = negative side, second =
  /// positive side. Empty when the plane does not cut the interior (every vertex on one side
  /// or on the plane).
  std::optional<std::pair<ConvexPolyhedron, ConvexPolyhedron>> split(const Plane& plane, int32_t plane_id) const;

  double volume() const;
  /// Volume of the part on the negative side of `plane` (sides by rounded distance: for cost
  /// estimates; split() decides topology). Cheap: clips faces only, no new topology.
  double volume_below(const Plane& plane) const;
  /// True when every face lies on an axis-aligned plane of `planes` (the cell is a box).
  bool is_box(const std::vector<Plane>& planes) const;
  Box3 bounds() const;
  Vec3 centroid() const;  ///< average of the vertices (inside, since convex)
  /// Area of face f.
  double face_area(size_t f) const;
  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<PolyFace>& faces() const { return faces_; }
  bool empty() const { return faces_.empty(); }

 private:
  std::vector<Vec3> vertices_;
  std::vector<PolyFace> faces_;
};

}  // namespace viewcells
