// The convex hulls of dynamic edits; the second translation unit that includes CGAL.
#include "viewcells/agvs/penumbra.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <cmath>

namespace viewcells {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

Vec3 to_vec(const Point& p) { return {p.x(), p.y(), p.z()}; }

/// Whether the points span a volume (CGAL's hull needs it): a base triangle from the points
/// far from the first one and from the line of the first two, then an exact coplanarity test.
bool spans_volume(const std::vector<Point>& pts) {
  if (pts.size() < 4) return false;
  size_t i1 = 0, i2 = 0;
  double best = 0;
  for (size_t i = 1; i < pts.size(); ++i)
    if (const double d = CGAL::squared_distance(pts[0], pts[i]); d > best) best = d, i1 = i;
  if (i1 == 0) return false;
  const Kernel::Line_3 line(pts[0], pts[i1]);
  best = 0;
  for (size_t i = 1; i < pts.size(); ++i)
    if (const double d = CGAL::squared_distance(line, pts[i]); d > best) best = d, i2 = i;
  if (i2 == 0 || CGAL::collinear(pts[0], pts[i1], pts[i2])) return false;
  for (const Point& p : pts)
    if (!CGAL::coplanar(pts[0], pts[i1], pts[i2], p)) return true;
  return false;
}

/// CGAL's convex hull of the points; false when they span no volume.
bool hull_mesh(std::span<const Vec3> points, Mesh& mesh) {
  std::vector<Point> pts;
  pts.reserve(points.size());
  for (const Vec3& p : points) pts.emplace_back(p.x, p.y, p.z);
  if (!spans_volume(pts)) return false;
  CGAL::convex_hull_3(pts.begin(), pts.end(), mesh);
  return true;
}

}  // namespace

ConvexRegion ConvexRegion::everything() {
  ConvexRegion r;
  r.everything_ = true;
  return r;
}

ConvexRegion ConvexRegion::hull(std::span<const Vec3> points) {
  ConvexRegion r;
  for (const Vec3& p : points) r.bounds_.extend(p);
  r.tolerance_ = 1e-9 * std::max(1.0, r.bounds_.diagonal());
  Mesh mesh;
  if (!hull_mesh(points, mesh)) return r;  // degenerate: the bounding box alone
  Vec3 centre{0, 0, 0};
  for (const auto v : mesh.vertices()) centre += to_vec(mesh.point(v));
  centre = centre / static_cast<double>(mesh.number_of_vertices());
  for (const auto f : mesh.faces()) {
    Vec3 corner[3];
    int n = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      if (n == 3) break;
      corner[n++] = to_vec(mesh.point(v));
    }
    if (n < 3) continue;
    Vec3 normal = cross(corner[1] - corner[0], corner[2] - corner[0]);
    const double len = length(normal);
    if (!(len > 0)) continue;
    normal = normal / len;
    double offset = dot(normal, corner[0]);
    if (dot(normal, centre) > offset) normal = normal * -1.0, offset = -offset;  // outward
    r.planes_.push_back({normal, offset});
  }
  return r;
}

bool ConvexRegion::may_intersect(const Box3& box) const {
  if (everything_) return true;
  if (box.empty()) return false;
  for (int k = 0; k < 3; ++k)
    if (box.lo[k] > bounds_.hi[k] + tolerance_ || box.hi[k] < bounds_.lo[k] - tolerance_) return false;
  for (const HalfSpace& h : planes_) {
    // The box corner furthest against the normal: outside when even it is outside.
    const Vec3 nearest{h.normal.x >= 0 ? box.lo.x : box.hi.x, h.normal.y >= 0 ? box.lo.y : box.hi.y,
                       h.normal.z >= 0 ? box.lo.z : box.hi.z};
    if (dot(h.normal, nearest) > h.offset + tolerance_) return false;
  }
  return true;
}

std::vector<Vec3> convex_hull_vertices(std::span<const Vec3> points) {
  Mesh mesh;
  if (!hull_mesh(points, mesh)) return {points.begin(), points.end()};
  std::vector<Vec3> out;
  for (const auto v : mesh.vertices()) out.push_back(to_vec(mesh.point(v)));
  return out;
}

ConvexRegion penumbra(std::span<const Vec3> occluder, const Box3& cell, double reach) {
  Box3 ob;
  for (const Vec3& p : occluder) ob.extend(p);
  const double gap = box_distance(ob, cell);
  // Touching (or inside) the cell, the object may hide anything from some point of it.
  if (!(gap > 1e-9 * std::max(1.0, reach))) return ConvexRegion::everything();
  const double b = reach / gap;
  std::vector<Vec3> pts(occluder.begin(), occluder.end());
  for (const Vec3& o : occluder)
    for (int k = 0; k < 8; ++k) {
      const Vec3 x{k & 1 ? cell.hi.x : cell.lo.x, k & 2 ? cell.hi.y : cell.lo.y, k & 4 ? cell.hi.z : cell.lo.z};
      pts.push_back(o + (o - x) * b);
    }
  return ConvexRegion::hull(pts);
}

}  // namespace viewcells
