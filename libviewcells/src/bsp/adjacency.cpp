/// Neighbouring leaves of the view space BSP, the merge candidates (view-cell-construction paper,
/// section 4.3).
#include "viewcells/bsp/adjacency.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace viewcells {
namespace {

/// A half-plane a x + b y + c <= 0 of the split plane's 2D frame.
struct HalfPlane {
  double a, b, c;
};

struct Poly2 {
  std::vector<std::pair<double, double>> pts;  // counter-clockwise
  std::vector<HalfPlane> sides;                 // the face as an intersection of half-planes
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

/// Area of the intersection of a convex polygon with a convex region given by half-planes
/// (Sutherland-Hodgman). `out` and `in` are scratch space, reused between calls.
double overlap_area(const std::vector<std::pair<double, double>>& subject, const std::vector<HalfPlane>& clip,
                    std::vector<std::pair<double, double>>& out, std::vector<std::pair<double, double>>& in) {
  out.assign(subject.begin(), subject.end());
  in.clear();
  for (size_t i = 0; i < clip.size() && !out.empty(); ++i) {
    const HalfPlane h = clip[i];
    auto inside = [&](const std::pair<double, double>& p) { return -(h.a * p.first + h.b * p.second + h.c); };
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

/// The sides of face `fi` of `cell` as half-planes of the frame (u, v) of `plane`: each edge is
/// where the face meets a neighbouring face, so its line is taken from that face's plane (a
/// direction known to the last bit) rather than from its two rounded end points, which on a
/// short edge point anywhere. Edges whose neighbouring plane is nearly parallel to `plane`, or
/// whose neighbour is not found, fall back to the line through the end points.
std::vector<HalfPlane> face_sides(const ConvexPolyhedron& cell, size_t fi, const std::vector<Plane>& planes,
                                  const Vec3& origin, const Vec3& u, const Vec3& v, bool reversed) {
  const std::vector<PolyFace>& faces = cell.faces();
  const std::vector<Vec3>& vs = cell.vertices();
  // The face that walks the edge b -> a (a neighbour walks a shared edge the other way); a
  // linear search, as cells have a few dozen edges.
  auto neighbour = [&](uint32_t a, uint32_t b) -> const PolyFace* {
    for (size_t g = 0; g < faces.size(); ++g) {
      const std::vector<uint32_t>& w = faces[g].vertices;
      for (size_t k = 0; k < w.size(); ++k)
        if (w[k] == b && w[(k + 1) % w.size()] == a) return g == fi ? nullptr : &faces[g];
    }
    return nullptr;
  };
  const PolyFace& f = faces[fi];
  std::vector<HalfPlane> out;
  for (size_t k = 0; k < f.vertices.size(); ++k) {
    const uint32_t a = f.vertices[k], b = f.vertices[(k + 1) % f.vertices.size()];
    if (const PolyFace* neighbour_face = neighbour(a, b)) {
      const PolyFace& g = *neighbour_face;
      const Plane& q = planes[g.plane];
      const double sign = g.outward_positive ? 1.0 : -1.0;  // inside: sign (n.x - d) <= 0
      const HalfPlane h{sign * dot(q.normal, u), sign * dot(q.normal, v), sign * (dot(q.normal, origin) - q.offset)};
      if (std::hypot(h.a, h.b) > 1e-6) {
        const double len = std::hypot(h.a, h.b);
        out.push_back({h.a / len, h.b / len, h.c / len});
        continue;
      }
    }
    // Through the end points. Unless reversed, the face runs counter-clockwise in (u, v), its
    // inside to the left of a->b: (b - a) x (p - a) >= 0.
    const double ax = dot(vs[a] - origin, u), ay = dot(vs[a] - origin, v), bx = dot(vs[b] - origin, u),
                 by = dot(vs[b] - origin, v);
    double na = by - ay, nb = -(bx - ax);  // right-hand normal of a->b: outward
    if (reversed) na = -na, nb = -nb;
    const double len = std::hypot(na, nb);
    if (!(len > 0)) continue;  // no direction: leave the line to the other sides
    out.push_back({na / len, nb / len, -(na * ax + nb * ay) / len});
  }
  return out;
}

}  // namespace

std::vector<LeafAdjacency> leaf_adjacency(const Subdivision& s, double min_relative_area) {
  return leaf_adjacency(s, s.leaves(), min_relative_area);
}

std::vector<LeafAdjacency> leaf_adjacency(const Subdivision& s, const std::vector<int32_t>& leaves,
                                          double min_relative_area) {
  const double min_area = min_relative_area * s.view_box.diagonal() * s.view_box.diagonal();
  // Faces on split planes (ids >= 6; 0..5 are the view box), by plane and side.
  using FaceList = std::vector<std::pair<int32_t, size_t>>;  // (leaf, face)
  std::vector<std::array<FaceList, 2>> faces(s.planes.size());  // [plane][positive side?]
  for (int32_t leaf : leaves) {
    const auto& cell_faces = s.cells[leaf].faces();
    for (size_t f = 0; f < cell_faces.size(); ++f) {
      const PolyFace& face = cell_faces[f];
      if (face.plane < 6) continue;
      // Outward along +normal means the leaf lies on the plane's negative side.
      faces[face.plane][face.outward_positive ? 0 : 1].push_back({leaf, f});
    }
  }
  std::vector<int32_t> shared_planes;  // planes with faces on both sides, ascending
  for (size_t k = 0; k < faces.size(); ++k)
    if (!faces[k][0].empty() && !faces[k][1].empty()) shared_planes.push_back(static_cast<int32_t>(k));
  // Each plane alone, in parallel; the pairs are then put together in plane order.
  std::vector<std::vector<LeafAdjacency>> found(shared_planes.size());
  tbb::parallel_for(size_t{0}, shared_planes.size(), [&](size_t k) {
    const int32_t plane_id = shared_planes[k];
    const Plane& plane = s.planes[plane_id];
    const Vec3 n = plane.normal;
    const Vec3 u = normalize(std::abs(n.x) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0}));
    const Vec3 v = cross(n, u);  // (u, v, n) right-handed: counter-clockwise about +n
    // 2D coordinates relative to the view box's centre projected onto the plane: areas of
    // faces far from the world's origin (a city at 1e5) keep their digits.
    const Vec3 centre = s.view_box.center();
    const Vec3 origin = centre - n * plane.distance(centre);
    // A face's corners in the plane's frame; `sides` (the face as half-planes) only for the
    // faces that are clipped against.
    auto project = [&](int32_t leaf, size_t f, bool reverse, bool sides) {
      Poly2 p;
      p.leaf = leaf;
      const ConvexPolyhedron& cell = s.cells[leaf];
      if (sides) p.sides = face_sides(cell, f, s.planes, origin, u, v, reverse);
      for (uint32_t id : cell.faces()[f].vertices) {
        const Vec3 d = cell.vertices()[id] - origin;
        p.pts.push_back({dot(d, u), dot(d, v)});
      }
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
    for (const auto& [leaf, f] : faces[plane_id][0]) a.push_back(project(leaf, f, false, false));
    for (const auto& [leaf, f] : faces[plane_id][1]) b.push_back(project(leaf, f, true, true));
    std::sort(b.begin(), b.end(), [](const Poly2& x, const Poly2& y) { return x.xmin < y.xmin; });
    // reach[i]: the largest xmax of b[0..i]. The faces before the first whose reach passes
    // p.xmin all end left of p.
    std::vector<double> reach(b.size());
    for (size_t i = 0; i < b.size(); ++i) reach[i] = std::max(b[i].xmax, i ? reach[i - 1] : -INFINITY);
    std::vector<std::pair<double, double>> clipped, scratch;
    for (const Poly2& p : a) {
      const size_t first = static_cast<size_t>(
          std::upper_bound(reach.begin(), reach.end(), p.xmin) - reach.begin());
      for (size_t i = first; i < b.size(); ++i) {
        const Poly2& q = b[i];
        if (q.xmin >= p.xmax) break;
        if (q.xmax <= p.xmin || q.ymin >= p.ymax || q.ymax <= p.ymin) continue;
        const double area = overlap_area(p.pts, q.sides, clipped, scratch);
        if (area > min_area) found[k].push_back({std::min(p.leaf, q.leaf), std::max(p.leaf, q.leaf), area});
      }
    }
  });
  // One entry per pair; a pair met on more than one plane sums its areas in plane order.
  std::vector<LeafAdjacency> out;
  for (const std::vector<LeafAdjacency>& f : found) out.insert(out.end(), f.begin(), f.end());
  std::stable_sort(out.begin(), out.end(),
                   [](const LeafAdjacency& x, const LeafAdjacency& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  size_t kept = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    if (kept && out[kept - 1].a == out[i].a && out[kept - 1].b == out[i].b) {
      out[kept - 1].area += out[i].area;
    } else {
      out[kept++] = out[i];
    }
  }
  out.resize(kept);
  return out;
}

}  // namespace viewcells
