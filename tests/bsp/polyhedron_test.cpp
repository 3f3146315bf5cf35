#include <gtest/gtest.h>

#include <cmath>

#include "viewcells/bsp/plane.h"
#include "viewcells/bsp/polyhedron.h"
#include "viewcells/core/rng.h"

namespace viewcells {
namespace {

TEST(Plane, SidesAreExact) {
  const Plane x = Plane::axis_aligned(0, 2.5);
  EXPECT_EQ(x.side({2.5, 7, -3}), 0);
  EXPECT_EQ(x.side({std::nextafter(2.5, 3.0), 0, 0}), 1);
  EXPECT_EQ(x.side({std::nextafter(2.5, 0.0), 0, 0}), -1);
  const Vec3 a{0.1, 0.2, 0.3}, b{1.7, 0.4, 0.9}, c{0.3, 1.9, 1.1};
  const Plane g = Plane::through(a, b, c);
  EXPECT_EQ(g.side(a), 0);
  EXPECT_EQ(g.side(b), 0);
  EXPECT_EQ(g.side(c), 0);
  // Integer points: the midpoint is representable and exactly on the plane; the next double
  // above it along the normal's dominant axis is not.
  const Plane h = Plane::through({0, 0, 0}, {2, 0, 2}, {0, 2, 0});  // z - x = 0, normal (-1,0,1)/sqrt2
  EXPECT_EQ(h.side({1, 0, 1}), 0);
  EXPECT_EQ(h.side({1, 0, std::nextafter(1.0, 2.0)}), 1);
  EXPECT_EQ(h.side({std::nextafter(1.0, 2.0), 0, 1}), -1);
  Rng rng(1);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 p{rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5)};
    const double d = g.distance(p);
    if (std::abs(d) > 1e-9) {
      EXPECT_EQ(g.side(p), d > 0 ? 1 : -1);
    }
  }
}

void expect_split_consistent(const ConvexPolyhedron& cell, const Plane& plane) {
  const auto halves = cell.split(plane, 99);
  ASSERT_TRUE(halves.has_value());
  const double v = cell.volume(), v0 = halves->first.volume(), v1 = halves->second.volume();
  EXPECT_GT(v0, 0);
  EXPECT_GT(v1, 0);
  EXPECT_NEAR((v0 + v1) / v, 1.0, 1e-9);
  EXPECT_NEAR(cell.volume_below(plane), v0, 1e-9 * v);
  // Every vertex of the negative half is on the negative side or on the plane, and vice versa.
  for (const Vec3& p : halves->first.vertices()) EXPECT_LE(plane.distance(p), 1e-9);
  for (const Vec3& p : halves->second.vertices()) EXPECT_GE(plane.distance(p), -1e-9);
  // The cap faces are on plane 99, one per half.
  int caps = 0;
  for (const PolyFace& f : halves->first.faces()) caps += f.plane == 99;
  EXPECT_EQ(caps, 1);
}

TEST(Polyhedron, BoxSplits) {
  const ConvexPolyhedron box = ConvexPolyhedron::box({{0, 0, 0}, {2, 3, 4}}, 0);
  EXPECT_DOUBLE_EQ(box.volume(), 24.0);
  EXPECT_EQ(box.faces().size(), 6u);
  double area = 0;
  for (size_t f = 0; f < 6; ++f) area += box.face_area(f);
  EXPECT_DOUBLE_EQ(area, 2 * (6 + 8 + 12));
  expect_split_consistent(box, Plane::axis_aligned(0, 0.5));
  expect_split_consistent(box, Plane::through({0, 0, 1}, {2, 0, 2}, {0, 3, 1.5}));
  EXPECT_FALSE(box.split(Plane::axis_aligned(1, 3.0), 7).has_value()) << "a face plane does not cut";
  EXPECT_FALSE(box.split(Plane::axis_aligned(1, 5.0), 7).has_value());
  // Through an edge and the opposite edge: the diagonal plane.
  expect_split_consistent(box, Plane::through({0, 0, 0}, {0, 0, 4}, {2, 3, 0}));
}

TEST(Polyhedron, RepeatedRandomSplitsKeepVolume) {
  Rng rng(5);
  std::vector<ConvexPolyhedron> cells{ConvexPolyhedron::box({{-1, -1, -1}, {1, 1, 1}}, 0)};
  double total = 8.0;
  for (int step = 0; step < 300; ++step) {
    const size_t i = rng.below(cells.size());
    const Vec3 c = cells[i].centroid();
    const Vec3 n = normalize(Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
    const Vec3 u = normalize(cross(n, Vec3{0.3, 0.5, 0.7})), w = cross(n, u);
    const auto halves = cells[i].split(Plane::through(c, c + u, c + w), 10 + step);
    if (!halves) continue;
    cells[i] = halves->first;
    cells.push_back(halves->second);
  }
  double sum = 0;
  for (const auto& c : cells) sum += c.volume();
  EXPECT_GT(cells.size(), 250u);
  EXPECT_NEAR(sum / total, 1.0, 1e-9);
}

TEST(Polyhedron, SplitAtAFaceWhoseCutVerticesRounded) {
  // Oblique cuts put new vertices on the box's edges by interpolation, which can round a
  // coordinate off the face they lie on (352 (1 - t) + 352 t != 352). Splitting then by that
  // face's own plane sees a face with vertices on the plane and one a hair beyond: the
  // children must still add up to the parent, with no face counted twice.
  Rng rng(11);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Box3 box{{2214.11, 205.518, -5.45443}, {2283.0, 352.0, 59.2391}};
    ConvexPolyhedron cell = ConvexPolyhedron::box(box, 0);
    for (int cut = 0; cut < 2; ++cut) {
      const Vec3 c = cell.centroid();
      const Vec3 n = normalize(Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
      const Vec3 u = normalize(cross(n, Vec3{0.3, 0.5, 0.7})), w = cross(n, u);
      const auto halves = cell.split(Plane::through(c, c + u * 100, c + w * 100), 10 + cut);
      if (halves) cell = halves->first;
    }
    for (int axis = 0; axis < 3; ++axis)
      for (double at : {box.lo[axis], box.hi[axis]}) {
        const Plane plane = Plane::axis_aligned(axis, at);
        bool neg = false, pos = false;
        for (const Vec3& v : cell.vertices()) neg |= plane.side(v) < 0, pos |= plane.side(v) > 0;
        if (!neg || !pos) continue;
        ++checked;  // the exact sides say the face's own plane cuts the cell
        const auto halves = cell.split(plane, 20);
        if (!halves) continue;  // refused as rounding: the cell stays whole
        const double v = cell.volume();
        ASSERT_NEAR(halves->first.volume() + halves->second.volume(), v, 1e-9 * v) << "trial " << trial;
      }
  }
  EXPECT_GT(checked, 10) << "the rounding case must occur for the test to mean anything";
}

TEST(Polyhedron, SliversFromNearlyParallelPlanes) {
  // Planes at angles of 1e-7 radians to each other, cutting thinner and thinner slices.
  ConvexPolyhedron cell = ConvexPolyhedron::box({{0, 0, 0}, {1, 1, 1}}, 0);
  double removed = 0;
  for (int k = 1; k <= 20; ++k) {
    const double tilt = 1e-7 * k, z = 0.5 + 1e-9 * k;
    const Plane p = Plane::through({0, 0, z}, {1, 0, z + tilt}, {0, 1, z});
    const auto halves = cell.split(p, 10 + k);
    if (!halves) continue;
    const double v = cell.volume();
    EXPECT_NEAR((halves->first.volume() + halves->second.volume()) / v, 1.0, 1e-9) << k;
    EXPECT_GE(halves->first.volume(), 0);
    removed += halves->second.volume();
    cell = halves->first;
  }
  EXPECT_NEAR((cell.volume() + removed), 1.0, 1e-9);
}

TEST(Polyhedron, LargeCoordinates) {
  const Vec3 o{1e5, -1e5, 1e5};
  const ConvexPolyhedron box = ConvexPolyhedron::box({o, o + Vec3{3, 2, 1}}, 0);
  EXPECT_NEAR(box.volume(), 6.0, 1e-9);
  expect_split_consistent(box, Plane::axis_aligned(2, o.z + 0.25));
  expect_split_consistent(box, Plane::through(o + Vec3{1, 0, 0}, o + Vec3{2, 2, 0}, o + Vec3{1, 0, 1}));
}

}  // namespace
}  // namespace viewcells
