/// Convex polyhedra, the cells of the view space BSP: split by a plane, volume, containment,
/// clipping (exact sides).
#include "viewcells/bsp/polyhedron.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "viewcells/core/error.h"

namespace viewcells {

ConvexPolyhedron ConvexPolyhedron::box(const Box3& b, int32_t first_plane_id) {
  ConvexPolyhedron p;
  for (int i = 0; i < 8; ++i)
    p.vertices_.push_back({i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z});
  // Counter-clockwise from outside; planes: -x, +x, -y, +y, -z, +z (axis-aligned, normal +axis).
  const uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (int f = 0; f < 6; ++f)
    p.faces_.push_back({{quads[f][0], quads[f][1], quads[f][2], quads[f][3]}, first_plane_id + f, (f & 1) == 1});
  return p;
}

namespace {

/// Welds the plane's section: points closer than `weld` (a small multiple of the rounding) are
/// one vertex (two cut edges leaving a vertex just beyond the plane end up that close). Only
/// the section can hold such pairs; the parent's vertices were welded when they were made.
/// Returns the representatives; `welded` maps every id to its own.
template <class Point>
std::vector<uint32_t> weld_section(std::vector<uint32_t> ids, const Point& point, double weld,
                                   std::map<uint32_t, uint32_t>& welded) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<uint32_t> section;
  for (uint32_t id : ids) {
    uint32_t rep = id;
    for (uint32_t r : section)
      if (length(point(r) - point(id)) <= weld) {
        rep = r;
        break;
      }
    if (rep == id) section.push_back(id);
    welded[id] = rep;
  }
  return section;
}

/// The section's points ordered by angle around their centre, counter-clockwise about n.
template <class Point>
std::vector<uint32_t> ordered_cap(const std::vector<uint32_t>& section, const Point& point, const Vec3& n) {
  Vec3 centre{};
  for (uint32_t id : section) centre += point(id);
  centre = centre / static_cast<double>(section.size());
  const Vec3 u_axis = normalize(std::abs(n.x) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0}));
  const Vec3 v_axis = cross(n, u_axis);
  std::vector<std::pair<double, uint32_t>> ordered;
  for (uint32_t id : section) {
    const Vec3 d = point(id) - centre;
    ordered.push_back({std::atan2(dot(d, v_axis), dot(d, u_axis)), id});
  }
  std::sort(ordered.begin(), ordered.end());
  std::vector<uint32_t> cap;
  for (const auto& [angle, id] : ordered) cap.push_back(id);
  return cap;
}

}  // namespace

std::optional<std::pair<ConvexPolyhedron, ConvexPolyhedron>> ConvexPolyhedron::split(const Plane& plane,
                                                                                      int32_t plane_id) const {
  const size_t nv = vertices_.size();
  std::vector<double> dist(nv);
  // Vertices made by earlier cuts are rounded: one meant to lie on a face's plane can sit a
  // few ulps off it, so a face can be a hair non-planar. A vertex within that rounding of
  // the plane does not make the plane cut, nor keep a face part that otherwise lies in it.
  double scale = 0;
  for (const Vec3& v : vertices_) scale = std::max({scale, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  const double eps = 64 * std::numeric_limits<double>::epsilon() * std::max(scale, std::abs(plane.offset));
  // Sides for topology: a vertex within the rounding of the plane is on it. A cut point made
  // on an edge that ends within rounding of the plane would be a near-duplicate of that end,
  // an edge of no length and arbitrary direction (it cost the adjacency 0.5% of its area).
  std::vector<int> eside(nv);
  bool any_neg = false, any_pos = false;
  for (size_t i = 0; i < nv; ++i) {
    dist[i] = plane.distance(vertices_[i]);
    eside[i] = std::abs(dist[i]) > eps ? plane.side(vertices_[i]) : 0;
    any_neg |= eside[i] < 0;
    any_pos |= eside[i] > 0;
  }
  if (!any_neg || !any_pos) return std::nullopt;

  // New vertices where edges cross the plane, shared by both children.
  std::vector<Vec3> cut_points;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> cut_of_edge;
  auto cut = [&](uint32_t u, uint32_t v) {
    const auto key = std::minmax(u, v);
    auto it = cut_of_edge.find(key);
    if (it != cut_of_edge.end()) return it->second;
    // Interpolate from the lower-index end so both faces sharing the edge get the same point.
    // Both ends lie beyond the rounding on opposite sides, so t is well inside (0, 1).
    const uint32_t a = key.first, b = key.second;
    const double t = std::clamp(dist[a] / (dist[a] - dist[b]), 0.0, 1.0);
    Vec3 p = vertices_[a] * (1.0 - t) + vertices_[b] * t;
    if (plane.axis >= 0) p[plane.axis] = plane.offset;  // exactly on an axis-aligned plane
    const uint32_t id = static_cast<uint32_t>(nv + cut_points.size());
    cut_points.push_back(p);
    cut_of_edge.emplace(key, id);
    return id;
  };

  struct FacePart {
    std::vector<uint32_t> poly;
    int32_t plane;
    bool outward_positive;
  };
  std::vector<FacePart> parts[2];
  std::vector<uint32_t> cap_vertices;  // parent-numbered (cuts numbered after the vertices)
  for (const PolyFace& f : faces_) {
    std::vector<uint32_t> poly[2];
    bool off_plane[2] = {false, false};  // the part has a vertex strictly on its side
    const size_t n = f.vertices.size();
    for (size_t k = 0; k < n; ++k) {
      const uint32_t u = f.vertices[k], v = f.vertices[(k + 1) % n];
      const int su = eside[u], sv = eside[v];
      off_plane[0] |= su < 0;
      off_plane[1] |= su > 0;
      if (su <= 0) poly[0].push_back(u);
      if (su >= 0) poly[1].push_back(u);
      if (su == 0) cap_vertices.push_back(u);
      if ((su < 0 && sv > 0) || (su > 0 && sv < 0)) {
        const uint32_t c = cut(u, v);
        poly[0].push_back(c);
        poly[1].push_back(c);
        cap_vertices.push_back(c);
      }
    }
    // A part with every vertex on the plane (up to rounding) lies in it, where the cap goes:
    // it is dropped.
    for (int s = 0; s < 2; ++s)
      if (poly[s].size() >= 3 && off_plane[s]) parts[s].push_back({std::move(poly[s]), f.plane, f.outward_positive});
  }

  auto point = [&](uint32_t id) { return id < nv ? vertices_[id] : cut_points[id - nv]; };
  std::map<uint32_t, uint32_t> welded;  // id -> representative
  const std::vector<uint32_t> section = weld_section(std::move(cap_vertices), point, 16 * eps, welded);
  auto rep = [&](uint32_t id) {
    const auto it = welded.find(id);
    return it == welded.end() ? id : it->second;
  };

  ConvexPolyhedron child[2];
  for (int s = 0; s < 2; ++s)
    for (FacePart& fp : parts[s]) {
      std::vector<uint32_t> poly;
      for (uint32_t id : fp.poly) {
        const uint32_t r = rep(id);
        if (poly.empty() || poly.back() != r) poly.push_back(r);
      }
      while (poly.size() > 1 && poly.front() == poly.back()) poly.pop_back();
      if (poly.size() >= 3) child[s].faces_.push_back({std::move(poly), fp.plane, fp.outward_positive});
    }

  // Cap: the plane's section, ordered by angle around its centre in a frame of the plane.
  if (section.size() < 3) return std::nullopt;  // touches the plane in an edge only
  std::vector<uint32_t> cap = ordered_cap(section, point, plane.normal);  // counter-clockwise about +n
  // Negative child: outward normal +n (counter-clockwise about +n); positive child: reversed.
  child[0].faces_.push_back({cap, plane_id, true});
  std::reverse(cap.begin(), cap.end());
  child[1].faces_.push_back({cap, plane_id, false});

  // Compact each child's vertices.
  for (ConvexPolyhedron& c : child) {
    std::map<uint32_t, uint32_t> remap;
    for (PolyFace& f : c.faces_)
      for (uint32_t& id : f.vertices) {
        auto [it, inserted] = remap.emplace(id, static_cast<uint32_t>(c.vertices_.size()));
        if (inserted) c.vertices_.push_back(point(id));
        id = it->second;
      }
  }
  if (child[0].faces_.size() < 4 || child[1].faces_.size() < 4) return std::nullopt;
  return std::make_pair(std::move(child[0]), std::move(child[1]));
}

double ConvexPolyhedron::volume() const {
  const Vec3 c = centroid();
  double v = 0;
  for (const PolyFace& f : faces_) {
    const Vec3 a = vertices_[f.vertices[0]] - c;
    for (size_t k = 1; k + 1 < f.vertices.size(); ++k)
      v += dot(a, cross(vertices_[f.vertices[k]] - c, vertices_[f.vertices[k + 1]] - c));
  }
  return v / 6.0;
}

double ConvexPolyhedron::volume_below(const Plane& plane) const {
  // Signed volume of the clipped faces seen from a point on the plane: the cap face, lying in
  // the plane, contributes nothing, so it need not be built.
  const Vec3 c0 = centroid();
  const Vec3 ref = c0 - plane.normal * plane.distance(c0);
  // Reused buffers: the subdivision calls this for every candidate position in a cell that is
  // not a box (hundreds of thousands of calls on a map), and two allocations each showed.
  thread_local std::vector<double> dist;
  thread_local std::vector<Vec3> poly;
  dist.resize(vertices_.size());
  for (size_t i = 0; i < vertices_.size(); ++i) dist[i] = plane.distance(vertices_[i]);
  double v = 0;
  for (const PolyFace& f : faces_) {
    poly.clear();
    const size_t n = f.vertices.size();
    for (size_t k = 0; k < n; ++k) {
      const uint32_t u = f.vertices[k], w = f.vertices[(k + 1) % n];
      if (dist[u] <= 0) poly.push_back(vertices_[u]);
      if ((dist[u] < 0 && dist[w] > 0) || (dist[u] > 0 && dist[w] < 0)) {
        const double t = dist[u] / (dist[u] - dist[w]);
        poly.push_back(vertices_[u] * (1.0 - t) + vertices_[w] * t);
      }
    }
    for (size_t k = 1; k + 1 < poly.size(); ++k)
      v += dot(poly[0] - ref, cross(poly[k] - ref, poly[k + 1] - ref));
  }
  return std::max(0.0, v / 6.0);
}

bool ConvexPolyhedron::is_box(const std::vector<Plane>& planes) const {
  for (const PolyFace& f : faces_)
    if (f.plane < 0 || planes[f.plane].axis < 0) return false;
  return !faces_.empty();
}

Box3 ConvexPolyhedron::bounds() const {
  Box3 b;
  for (const Vec3& p : vertices_) b.extend(p);
  return b;
}

Vec3 ConvexPolyhedron::centroid() const {
  Vec3 c{};
  for (const Vec3& p : vertices_) c += p;
  return vertices_.empty() ? c : c / static_cast<double>(vertices_.size());
}

double ConvexPolyhedron::face_area(size_t fi) const {
  const PolyFace& f = faces_[fi];
  Vec3 sum{};
  const Vec3 a = vertices_[f.vertices[0]];
  for (size_t k = 1; k + 1 < f.vertices.size(); ++k)
    sum += cross(vertices_[f.vertices[k]] - a, vertices_[f.vertices[k + 1]] - a);
  return 0.5 * length(sum);
}

}  // namespace viewcells
