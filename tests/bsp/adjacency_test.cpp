// Neighbours of BSP leaves on hostile split planes, built without Embree or sampling, so that
// every CPU runs exactly these cells: planes through existing vertices or within rounding of
// them, nearly parallel and nearly coincident planes, slivers, city coordinates.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <map>

#include "viewcells/bsp/adjacency.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/core/rng.h"

namespace viewcells {
namespace {

/// A subdivision of `box` made by hand: every plane of `cuts` splits, in turn, every current
/// leaf it cuts (each split with its own plane id, as subdivide() numbers them).
Subdivision split_all(const Box3& box, const std::vector<Plane>& cuts) {
  Subdivision s;
  s.view_box = box;
  s.planes = {Plane::axis_aligned(0, box.lo.x), Plane::axis_aligned(0, box.hi.x), Plane::axis_aligned(1, box.lo.y),
              Plane::axis_aligned(1, box.hi.y), Plane::axis_aligned(2, box.lo.z), Plane::axis_aligned(2, box.hi.z)};
  s.nodes.push_back({});
  s.cells.push_back(ConvexPolyhedron::box(box, 0));
  s.segments.emplace_back();
  for (const Plane& plane : cuts) {
    for (int32_t leaf : s.leaves()) {
      const int32_t id = static_cast<int32_t>(s.planes.size());
      auto halves = s.cells[leaf].split(plane, id);
      if (!halves) continue;
      s.planes.push_back(plane);
      const int32_t first = static_cast<int32_t>(s.nodes.size());
      s.nodes[leaf].plane = id;
      s.nodes[leaf].child[0] = first;
      s.nodes[leaf].child[1] = first + 1;
      for (int k = 0; k < 2; ++k) {
        BspNode n;
        n.parent = leaf;
        s.nodes.push_back(n);
        s.segments.emplace_back();
      }
      s.cells.push_back(std::move(halves->first));
      s.cells.push_back(std::move(halves->second));
      s.cells[leaf] = ConvexPolyhedron();
      s.splits.push_back({leaf, 0, 0});
    }
  }
  return s;
}

/// Invariants of the cells and their neighbours: every cell is closed (each directed edge has
/// its reverse in another face) with no two vertices within rounding of each other (a sliver
/// 1e-12 thick is legitimate); the leaf
/// volumes add up to the box; on every split plane the faces on its two sides have the same
/// area, and the neighbours' shared areas add up to it, all to 1e-9 relative.
void expect_exact_adjacency(const Subdivision& s) {
  const std::vector<int32_t> leaves = s.leaves();
  const double scale = std::max(length(s.view_box.lo), length(s.view_box.hi));
  double volume = 0;
  std::map<int32_t, double> side_area[2];
  for (int32_t l : leaves) {
    const ConvexPolyhedron& c = s.cells[l];
    volume += c.volume();
    const auto& vs = c.vertices();
    for (size_t i = 0; i < vs.size(); ++i)
      for (size_t j = i + 1; j < vs.size(); ++j)
        EXPECT_GT(length(vs[i] - vs[j]), 64 * DBL_EPSILON * scale) << "leaf " << l << ": near-duplicate vertices " << i << ", " << j;
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (const PolyFace& f : c.faces())
      for (size_t k = 0; k < f.vertices.size(); ++k) ++edges[{f.vertices[k], f.vertices[(k + 1) % f.vertices.size()]}];
    for (const auto& [e, count] : edges) {
      EXPECT_EQ(count, 1) << "leaf " << l << ": edge used twice in one direction";
      EXPECT_EQ(edges.count({e.second, e.first}), 1u) << "leaf " << l << ": open edge " << e.first << "-" << e.second;
    }
    for (size_t f = 0; f < c.faces().size(); ++f) {
      const PolyFace& face = c.faces()[f];
      if (face.plane >= 6) side_area[face.outward_positive ? 0 : 1][face.plane] += c.face_area(f);
    }
  }
  EXPECT_NEAR(volume / s.view_box.volume(), 1.0, 1e-9);
  double faces_total = 0;
  for (const auto& [plane, area] : side_area[0]) {
    const double other = side_area[1].count(plane) ? side_area[1].at(plane) : 0.0;
    EXPECT_NEAR(other / area, 1.0, 1e-9) << "plane " << plane;
    faces_total += area;
  }
  EXPECT_EQ(side_area[0].size(), side_area[1].size());
  double shared = 0;
  for (const LeafAdjacency& e : leaf_adjacency(s)) {
    EXPECT_LT(e.a, e.b);
    EXPECT_GT(e.area, 0);
    shared += e.area;
  }
  EXPECT_NEAR(shared / faces_total, 1.0, 1e-9);
}

/// A vertex of some leaf, chosen by `rng`.
Vec3 some_vertex(const Subdivision& s, Rng& rng) {
  const std::vector<int32_t> leaves = s.leaves();
  const ConvexPolyhedron& c = s.cells[leaves[rng.next_u64() % leaves.size()]];
  return c.vertices()[rng.next_u64() % c.vertices().size()];
}

Vec3 nudge(const Vec3& p, int ulps) {
  Vec3 q = p;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < std::abs(ulps); ++i) q[k] = std::nextafter(q[k], ulps > 0 ? INFINITY : -INFINITY);
  return q;
}

/// Planes through existing cell vertices, exactly or a few ulps off, in random directions.
std::vector<Plane> planes_through_vertices(const Box3& box, uint64_t seed, int count) {
  Rng rng(seed);
  std::vector<Plane> cuts = {Plane::axis_aligned(0, 0.5 * (box.lo.x + box.hi.x)),
                             Plane::axis_aligned(1, 0.5 * (box.lo.y + box.hi.y))};
  Subdivision s = split_all(box, cuts);
  for (int i = 0; i < count; ++i) {
    const Vec3 a = nudge(some_vertex(s, rng), static_cast<int>(rng.next_u64() % 5) - 2);
    const Vec3 b = some_vertex(s, rng);
    const Vec3 e = box.extent();
    const Vec3 c = box.lo + Vec3{rng.uniform(0, e.x), rng.uniform(0, e.y), rng.uniform(0, e.z)};
    if (length(cross(b - a, c - a)) < 1e-6 * box.diagonal() * box.diagonal()) continue;
    cuts.push_back(Plane::through(a, b, c));
    s = split_all(box, cuts);
  }
  return cuts;
}

TEST(Adjacency, PlanesThroughAndNearVertices) {
  for (const Vec3& offset : {Vec3{0, 0, 0}, Vec3{1e5, -2e5, 30}}) {
    const Box3 box{offset + Vec3{0, 0, 0}, offset + Vec3{10, 7, 3}};
    for (uint64_t seed : {1, 2, 3}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", offset " + std::to_string(offset.x));
      expect_exact_adjacency(split_all(box, planes_through_vertices(box, seed, 6)));
    }
  }
}

TEST(Adjacency, NearlyParallelAndNearlyCoincidentPlanes) {
  const Box3 box{{0, 0, 0}, {4, 4, 4}};
  std::vector<Plane> cuts = {Plane::axis_aligned(0, 2)};
  // Tilted from x = 2 by 1e-7, 1e-10 and 1e-13 radians, through points on it.
  for (double tilt : {1e-7, 1e-10, 1e-13})
    cuts.push_back(Plane::through({2, 0, 0}, {2 + tilt * 4, 4, 0}, {2, 0, 4}));
  // A plane a few ulps beside x = 2 (nearly coincident), and slivers 1e-9 and 1e-12 thick.
  cuts.push_back(Plane::through(nudge({2, 0, 0}, 3), nudge({2, 4, 0}, 3), nudge({2, 0, 4}, 3)));
  cuts.push_back(Plane::axis_aligned(1, 1));
  cuts.push_back(Plane::axis_aligned(1, 1 + 1e-9));
  cuts.push_back(Plane::axis_aligned(1, 1 + 1e-9 + 1e-12));
  // A diagonal through box edges and cell corners, and the same shifted by one ulp.
  cuts.push_back(Plane::through({0, 0, 0}, {4, 4, 0}, {0, 0, 4}));
  cuts.push_back(Plane::through(nudge({0, 0, 0}, 1), nudge({4, 4, 0}, 1), nudge({0, 0, 4}, 1)));
  cuts.push_back(Plane::axis_aligned(2, 2));
  expect_exact_adjacency(split_all(box, cuts));
}

TEST(Adjacency, RotatedGridOfWallsOnSplitPlanes) {
  // A rotated grid (walls on split planes of a rotated level) cut also by the axis planes
  // through its crossing points, at city coordinates.
  const Vec3 o{3e5, 1e5, 0};
  const Box3 box{o, o + Vec3{20, 20, 5}};
  const double angle = 0.3;
  const Vec3 dx{std::cos(angle), std::sin(angle), 0}, dy{-std::sin(angle), std::cos(angle), 0};
  const Vec3 centre = o + Vec3{10, 10, 0};
  std::vector<Plane> cuts;
  for (int k = -3; k <= 3; ++k) {
    const Vec3 p = centre + dx * (2.5 * k), q = centre + dy * (2.5 * k);
    cuts.push_back(Plane::through(p, p + dy, p + Vec3{0, 0, 1}));
    cuts.push_back(Plane::through(q, q + dx, q + Vec3{0, 0, 1}));
    cuts.push_back(Plane::axis_aligned(0, (centre + dx * (2.5 * k) + dy * (2.5 * k)).x));
  }
  cuts.push_back(Plane::axis_aligned(2, 1.7));
  expect_exact_adjacency(split_all(box, cuts));
}

}  // namespace
}  // namespace viewcells
