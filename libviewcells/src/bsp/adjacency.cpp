#include "viewcells/bsp/adjacency.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace viewcells {
namespace {

struct Poly2 {
  std::vector<std::pair<double, double>> pts;  // counter-clockwise
  double xmin, xmax, ymin, ymax;
  int32_t leaf;
};

double area2(const std::vector<std::pair<double, double>>& p) {
  double a = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const auto& u = p[i];
    const auto& v = p[(i + 1) % p.size()];
    a += u.first * v.second - v.first * u.second;
  }
  return 0.5 * a;
}

/// Area of the intersection of two convex counter-clockwise polygons (Sutherland-Hodgman).
double overlap_area(const std::vector<std::pair<double, double>>& subject,
                    const std::vector<std::pair<double, double>>& clip) {
  std::vector<std::pair<double, double>> out = subject, in;
  for (size_t i = 0; i < clip.size() && !out.empty(); ++i) {
    const auto a = clip[i], b = clip[(i + 1) % clip.size()];
    auto inside = [&](const std::pair<double, double>& p) {
      return (b.first - a.first) * (p.second - a.second) - (b.second - a.second) * (p.first - a.first);
    };
    in.swap(out);
    out.clear();
    for (size_t k = 0; k < in.size(); ++k) {
      const auto p = in[k], q = in[(k + 1) % in.size()];
      const double dp = inside(p), dq = inside(q);
      if (dp >= 0) out.push_back(p);
      if ((dp >= 0) != (dq >= 0)) {
        const double t = dp / (dp - dq);
        out.push_back({p.first + t * (q.first - p.first), p.second + t * (q.second - p.second)});
      }
    }
  }
  return out.size() >= 3 ? std::abs(area2(out)) : 0.0;
}

}  // namespace

std::vector<LeafAdjacency> leaf_adjacency(const Subdivision& s, double min_relative_area) {
  return leaf_adjacency(s, s.leaves(), min_relative_area);
}

std::vector<LeafAdjacency> leaf_adjacency(const Subdivision& s, const std::vector<int32_t>& leaves,
                                          double min_relative_area) {
  const double min_area = min_relative_area * s.view_box.diagonal() * s.view_box.diagonal();
  // Faces on split planes (ids >= 6; 0..5 are the view box), by plane and side.
  std::map<int32_t, std::vector<std::pair<int32_t, size_t>>> faces[2];  // [positive side?][plane] -> (leaf, face)
  for (int32_t leaf : leaves) {
    const auto& cell_faces = s.cells[leaf].faces();
    for (size_t f = 0; f < cell_faces.size(); ++f) {
      const PolyFace& face = cell_faces[f];
      if (face.plane < 6) continue;
      // Outward along +normal means the leaf lies on the plane's negative side.
      faces[face.outward_positive ? 0 : 1][face.plane].push_back({leaf, f});
    }
  }
  std::map<std::pair<int32_t, int32_t>, double> shared;
  for (const auto& [plane_id, neg_faces] : faces[0]) {
    const auto it = faces[1].find(plane_id);
    if (it == faces[1].end()) continue;
    const Plane& plane = s.planes[plane_id];
    const Vec3 n = plane.normal;
    const Vec3 u = normalize(std::abs(n.x) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0}));
    const Vec3 v = cross(n, u);  // (u, v, n) right-handed: counter-clockwise about +n
    auto project = [&](int32_t leaf, size_t f, bool reverse) {
      Poly2 p;
      p.leaf = leaf;
      const ConvexPolyhedron& cell = s.cells[leaf];
      for (uint32_t id : cell.faces()[f].vertices) p.pts.push_back({dot(cell.vertices()[id], u), dot(cell.vertices()[id], v)});
      if (reverse) std::reverse(p.pts.begin(), p.pts.end());
      p.xmin = p.ymin = INFINITY;
      p.xmax = p.ymax = -INFINITY;
      for (const auto& [x, y] : p.pts) {
        p.xmin = std::min(p.xmin, x), p.xmax = std::max(p.xmax, x);
        p.ymin = std::min(p.ymin, y), p.ymax = std::max(p.ymax, y);
      }
      return p;
    };
    // Faces of leaves on the negative side point along +n (counter-clockwise about +n already);
    // those on the positive side point along -n, so reverse them.
    std::vector<Poly2> a, b;
    for (const auto& [leaf, f] : neg_faces) a.push_back(project(leaf, f, false));
    for (const auto& [leaf, f] : it->second) b.push_back(project(leaf, f, true));
    std::sort(b.begin(), b.end(), [](const Poly2& x, const Poly2& y) { return x.xmin < y.xmin; });
    for (const Poly2& p : a) {
      for (const Poly2& q : b) {
        if (q.xmin >= p.xmax) break;
        if (q.xmax <= p.xmin || q.ymin >= p.ymax || q.ymax <= p.ymin) continue;
        const double area = overlap_area(p.pts, q.pts);
        if (area > min_area) shared[{std::min(p.leaf, q.leaf), std::max(p.leaf, q.leaf)}] += area;
      }
    }
  }
  std::vector<LeafAdjacency> out;
  out.reserve(shared.size());
  for (const auto& [pair, area] : shared) out.push_back({pair.first, pair.second, area});
  return out;
}

}  // namespace viewcells
