#pragma once
// Walking a segment down a BSP: the one rule by which a segment is divided among the leaves,
// for the subdivision's own trees and for the compact copies that locate segments fast.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

#include "viewcells/bsp/plane.h"
#include "viewcells/core/vec3.h"

namespace viewcells::bsp_detail {

/// Where a plane cuts the part a + t (b - a), t in [t0, t1], whose ends are at signed
/// distances d0 and d1 on opposite sides: t on the grid of multiples of 2^-31 (exact in
/// double, 0 and 1 included), the point nearest the plane's rounded crossing, kept within
/// [t0, t1]. The subdivision stores its parts' t in 31-bit fixed point (half the memory of
/// doubles); every walk down a tree cuts on the same grid, so that a segment is divided among
/// the leaves exactly as the subdivision divided it. The grid moves a cut by at most
/// |b - a| / 2^32 along the segment.
inline double cut_parameter(double t0, double t1, double d0, double d1) {
  const double t = t0 + (t1 - t0) * (d0 / (d0 - d1));
  const double on_grid = t > 0 ? std::nearbyint(std::min(t, 1.0) * 0x1p31) * 0x1p-31 : 0.0;
  return std::clamp(on_grid, t0, t1);
}

/// Walks the segment a-b down `tree`: stop(n, t0, t1) is asked at every node the segment has
/// length in (the part a + t (b - a), t in [t0, t1]), and the walk goes below n only when it
/// returns false; it must return true at leaves. Every node visited leads to at least one
/// leaf (a part not in a plane has an end off it), so a walk that stops early at a node
/// reports what the walk below it would reach. `tree` gives, per inner node n, axis(n) (the
/// axis of an axis-aligned plane, else -1), offset(n) (an axis-aligned plane's coordinate),
/// plane(n) (the plane, for the others) and child(n, k); the walk starts at node `root`.
template <class Tree, class Stop>
void walk_segment(const Tree& tree, const Vec3& a, const Vec3& b,
                  std::vector<std::tuple<int32_t, double, double>>& stack, Stop&& stop, int32_t root = 0) {
  // The node visited next is kept in registers, and only the part left for later goes on the
  // stack (a push followed at once by its pop cost a stalled load of what was just stored);
  // the nodes are visited in the order of a walk that pushes both children, the second first.
  stack.clear();
  int32_t n = root;
  double t0 = 0.0, t1 = 1.0;
  for (;;) {
    if (stop(n, t0, t1)) {
      if (stack.empty()) return;
      std::tie(n, t0, t1) = stack.back();
      stack.pop_back();
      continue;
    }
    int s0, s1;
    double d0, d1;
    if (const int axis = tree.axis(n); axis >= 0) {
      // The one coordinate an axis-aligned plane reads, rounded exactly as in the whole point
      // below; its distance is that coordinate minus the offset, as Plane::distance gives it.
      const double offset = tree.offset(n);
      const double c0 = a[axis] * (1.0 - t0) + b[axis] * t0, c1 = a[axis] * (1.0 - t1) + b[axis] * t1;
      s0 = c0 > offset ? 1 : (c0 < offset ? -1 : 0);
      s1 = c1 > offset ? 1 : (c1 < offset ? -1 : 0);
      d0 = c0 - offset;
      d1 = c1 - offset;
    } else {
      const Plane& plane = tree.plane(n);
      const Vec3 p0 = a * (1.0 - t0) + b * t0, p1 = a * (1.0 - t1) + b * t1;
      s0 = plane.side(p0);
      s1 = plane.side(p1);
      d0 = plane.distance(p0);
      d1 = plane.distance(p1);
    }
    if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {  // as the subdivision's own splits
      const double t = cut_parameter(t0, t1, d0, d1);
      stack.emplace_back(tree.child(n, s0 < 0 ? 0 : 1), t0, t);
      n = tree.child(n, s0 < 0 ? 1 : 0);
      t0 = t;
      continue;
    }
    const bool in_plane = s0 == 0 && s1 == 0;
    const bool neg = in_plane || s0 < 0 || s1 < 0, pos = in_plane || s0 > 0 || s1 > 0;
    if (neg && pos) stack.emplace_back(tree.child(n, 0), t0, t1);
    n = tree.child(n, pos ? 1 : 0);
  }
}

}  // namespace viewcells::bsp_detail
