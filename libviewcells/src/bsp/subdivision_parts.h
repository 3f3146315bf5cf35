#pragma once
// The subdivision's working data (subdivision.cpp, view-cell-construction paper section 4.2):
// segment parts in a node (SegRef, SegEnds), first-seen marks (Marks), the extents an axis
// sweep reads (NodeExtents, ExtentSlots, PointMarks), distinct candidate positions
// (DrawnSet), exact sides against geometry-aligned planes (FilteredSide, ObjectExtremes), and
// what evaluating a node's candidate planes gives (Candidate, Evaluation). Internal to the
// subdivision's files (subdivision_builder*.cpp).
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "viewcells/bsp/plane.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/core/default_init.h"
#include "viewcells/sampling/segments.h"

namespace viewcells::subdivision_detail {

/// Smallest part of a cell a split may cut off, relative to the cell's volume.
constexpr double kMinPart = 1e-9;

/// The part of segment `id` in a node: a + t (b - a), t in [t0, t1], with t in 31-bit fixed
/// point (q / 2^31, on the grid bsp_detail::cut_parameter cuts on). Twelve bytes instead of 24
/// with doubles: the leaves of the city at 50k cells hold 47.5M parts, and every split writes
/// its cell's parts into its children, so their size is memory traffic and page faults (the
/// city's subdivision to 50k cells: peak memory 1.16 GB against 1.73 GB).
struct SegRef {
  static constexpr uint32_t kOne = 1u << 31;
  uint32_t id;
  uint32_t q0, q1;
  double t0() const { return static_cast<double>(q0) * 0x1p-31; }
  double t1() const { return static_cast<double>(q1) * 0x1p-31; }
};
static_assert(sizeof(SegRef) == 12);

/// One segment's end points and objects in one cache line: the subdivision reads a segment by
/// id once per node it lies in (tens of millions of parts at 50k cells), and the segment
/// set's eight separate arrays would cost eight cache misses each time.
struct alignas(64) SegEnds {
  Vec3 a, b;
  uint32_t object_a, object_b;
  uint32_t triangle_a, triangle_b;  ///< the triangles hit at a and b (kNoObject: none)
  /// The point a + t (b - a), rounded the same way wherever the subdivision needs it.
  Vec3 at(double t) const { return a * (1.0 - t) + b * t; }
};

/// The triangle hit at an end of segment i; kNoObject also where a segment set carries no
/// triangles (built by hand, as some tests do).
inline uint32_t triangle_of(const RawVector<uint32_t>& triangles, size_t i) {
  return i < triangles.size() ? triangles[i] : kNoObject;
}

/// Which children a segment part goes to, from the exact sides of its two ends:
/// bit 0 negative, bit 1 positive.
inline int classify(int s0, int s1) {
  if (s0 == 0 && s1 == 0) return 3;  // lies in the plane: length in both closed halves
  return ((s0 < 0 || s1 < 0) ? 1 : 0) | ((s0 > 0 || s1 > 0) ? 2 : 0);
}

/// First-seen marks per object, reset in O(1) by bumping an epoch.
struct Marks {
  std::vector<uint32_t> stamp;
  uint32_t epoch = 0;
  void reset(size_t n) {
    if (stamp.size() < n) stamp.assign(n, 0);
    if (++epoch == 0) {
      std::fill(stamp.begin(), stamp.end(), 0);
      epoch = 1;
    }
  }
  /// True the first time object o is seen (never for kNoObject).
  bool first(uint32_t o) {
    if (o == kNoObject || stamp[o] == epoch) return false;
    stamp[o] = epoch;
    return true;
  }
  /// True once object o has been seen (always for kNoObject): adding it gives 0.
  bool seen(uint32_t o) const { return o == kNoObject || stamp[o] == epoch; }
  /// Cost added by seeing object o (0 if already seen or none).
  double add(uint32_t o, const double* r) {
    if (o == kNoObject || stamp[o] == epoch) return 0.0;
    stamp[o] = epoch;
    return r[o];
  }
};

/// A segment part that is a point along an axis (its two ends share the coordinate there): on
/// that axis it lies in the plane through its coordinate, so the sweep takes it apart.
struct PointPart {
  double at;
  uint32_t object_a, object_b;
};

/// What the axis sweep needs of a node's segment parts, from one pass over them: per object
/// seen, along each axis, the lowest low end and the highest high end of its parts that have
/// length along that axis (+inf and -inf when none has), with the objects in the order the
/// parts first name them; and, per axis, the parts that are points along it. An object is on
/// the negative side of x = c once one of its parts begins below c, on the positive side while
/// one ends above it, so these extremes decide both sides' PVSs at every position.
struct NodeExtents {
  struct Range {
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  };
  std::vector<uint32_t> objects;
  std::vector<Range> ranges;  ///< per entry of objects
  /// Per entry of objects: 1 when it and the next entry were first seen at the two ends of
  /// one part (so that r(PVS) adds their costs in the order a pass over the parts does).
  std::vector<uint8_t> paired;
  std::array<std::vector<PointPart>, 3> points;
  /// r(PVS) of the parts: each object's r once, added as a pass over the parts adds them.
  double pvs_cost(const std::vector<double>& r) const {
    double c = 0;
    for (size_t i = 0; i < objects.size(); ++i) {
      if (paired[i]) {
        c += r[objects[i]] + r[objects[i + 1]];
        ++i;
      } else {
        c += r[objects[i]];
      }
    }
    return c;
  }
};

/// Object -> its entry in the NodeExtents being built; reset in O(1) by bumping an epoch.
/// The ranges are kept per object id while a NodeExtents is built (no indirection, no growing
/// array on the way) and copied into it in order by finish().
struct ExtentSlots {
  std::vector<uint32_t> stamp;
  std::vector<NodeExtents::Range> range;  ///< per object; valid where stamped
  uint32_t epoch = 0;
  void reset(size_t n) {
    if (stamp.size() < n) {
      stamp.assign(n, 0);
      range.resize(n);
    }
    if (++epoch == 0) {
      std::fill(stamp.begin(), stamp.end(), 0);
      epoch = 1;
    }
  }
  /// The range of object o, listed in `into` (with empty ranges) the first time.
  NodeExtents::Range& entry(uint32_t o, NodeExtents& into) {
    if (stamp[o] != epoch) {
      stamp[o] = epoch;
      into.objects.push_back(o);
      into.paired.push_back(0);
      range[o] = NodeExtents::Range();
    }
    return range[o];
  }
  /// Writes the ranges of the objects listed in `into` (after adding parts or merging).
  void finish(NodeExtents& into) const {
    into.ranges.resize(into.objects.size());
    for (size_t i = 0; i < into.objects.size(); ++i) into.ranges[i] = range[into.objects[i]];
  }
  /// Adds the segment part p0-p1 seen by objects a and b.
  void add_part(const Vec3& p0, const Vec3& p1, uint32_t a, uint32_t b, NodeExtents& into) {
    if (a == kNoObject && b == kNoObject) return;
    double lo[3], hi[3];
    for (int axis = 0; axis < 3; ++axis) {
      const double c0 = p0[axis], c1 = p1[axis];
      if (c0 == c1) {  // a point along this axis: listed apart, no range
        into.points[axis].push_back({c0, a, b});
        lo[axis] = INFINITY;
        hi[axis] = -INFINITY;
      } else {
        lo[axis] = std::min(c0, c1);
        hi[axis] = std::max(c0, c1);
      }
    }
    const size_t before = into.objects.size();
    for (uint32_t o : {a, b == a ? kNoObject : b}) {
      if (o == kNoObject) continue;
      NodeExtents::Range& r = entry(o, into);
      for (int axis = 0; axis < 3; ++axis) {
        r.lo[axis] = std::min(r.lo[axis], lo[axis]);
        r.hi[axis] = std::max(r.hi[axis], hi[axis]);
      }
    }
    if (into.objects.size() == before + 2) into.paired[before] = 1;
  }
  /// Adds the extents of later parts, keeping the order objects were first seen in.
  void merge(const NodeExtents& later, NodeExtents& into) {
    for (size_t i = 0; i < later.objects.size(); ++i) {
      // A pair stays a pair only if both are new here (else the part adds one cost alone).
      const bool first_seen = stamp[later.objects[i]] != epoch;
      NodeExtents::Range& r = entry(later.objects[i], into);
      if (first_seen && later.paired[i] && stamp[later.objects[i + 1]] != epoch) into.paired.back() = 1;
      const NodeExtents::Range& l = later.ranges[i];
      for (int axis = 0; axis < 3; ++axis) {
        r.lo[axis] = std::min(r.lo[axis], l.lo[axis]);
        r.hi[axis] = std::max(r.hi[axis], l.hi[axis]);
      }
    }
    for (int axis = 0; axis < 3; ++axis)
      into.points[axis].insert(into.points[axis].end(), later.points[axis].begin(), later.points[axis].end());
  }
};

/// Per object, the position indices its point parts along an axis give it (see
/// Builder::side_costs); reset in O(1) by bumping an epoch.
struct PointMarks {
  std::vector<uint32_t> stamp;
  std::vector<int32_t> first, last;
  std::vector<double> padded;  ///< scratch: the positions padded to a power of two
  uint32_t epoch = 0;
  void reset(size_t n) {
    if (stamp.size() < n) {
      stamp.assign(n, 0);
      first.resize(n);
      last.resize(n);
    }
    if (++epoch == 0) {
      std::fill(stamp.begin(), stamp.end(), 0);
      epoch = 1;
    }
  }
  void touch(uint32_t o, int32_t jl, int32_t jr) {
    if (o == kNoObject) return;
    if (stamp[o] != epoch) {
      stamp[o] = epoch;
      first[o] = jl;
      last[o] = jr;
      return;
    }
    first[o] = std::min(first[o], jl);
    last[o] = std::max(last[o], jr);
  }
};

/// A set of doubles (open addressing, cleared in O(1) by an epoch), for drawing distinct
/// candidate positions.
class DrawnSet {
 public:
  void reset(size_t k) {
    size_t size = 16;
    while (size < 8 * k) size *= 2;
    if (stamp_.size() != size) {
      stamp_.assign(size, 0);
      value_.assign(size, 0.0);
      epoch_ = 0;
    }
    if (++epoch_ == 0) {
      std::fill(stamp_.begin(), stamp_.end(), 0);
      epoch_ = 1;
    }
  }
  /// True when v was not in the set (and is now).
  bool insert(double v) {
    v += 0.0;  // -0 and +0 are one position
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    const size_t mask = stamp_.size() - 1;
    for (size_t h = (bits * 0x9E3779B97F4A7C15ull) >> 40;; ++h) {
      const size_t slot = h & mask;
      if (stamp_[slot] != epoch_) {
        stamp_[slot] = epoch_;
        value_[slot] = v;
        return true;
      }
      if (value_[slot] == v) return false;
    }
  }

 private:
  std::vector<uint32_t> stamp_;
  std::vector<double> value_;
  uint32_t epoch_ = 0;
};

/// The exact side of points against a geometry-aligned plane through p, q, r, decided as
/// Plane::side (CGAL's orientation predicate) decides it, but mostly without the call: the
/// determinant of (q - p, r - p, s - p) in double, evaluated as CGAL's determinant() does
/// with s - p in the last column (so the 2x2 minors of q - p and r - p are computed once per
/// plane), against twice the error bound of CGAL's semi-static filter for it; Plane::side
/// where that bound does not decide. The bound grows with |s - p|, so the bound for the corner
/// of the points' box farthest from p holds for all of them: it is tried first, and the
/// point's own bound only where it does not decide (the same sign either way).
class FilteredSide {
 public:
  FilteredSide(const Plane& plane, const Box3& points) : plane_(plane), p_(plane.points[0]) {
    const Vec3 pq = plane.points[1] - p_, pr = plane.points[2] - p_;
    m01_ = pq.x * pr.y - pq.y * pr.x;
    m02_ = pq.x * pr.z - pq.z * pr.x;
    m12_ = pq.y * pr.z - pq.z * pr.y;
    for (int k = 0; k < 3; ++k) max_[k] = std::max(std::abs(pq[k]), std::abs(pr[k]));
    double box_eps = 2 * 5.1107127829973299e-15;
    for (int k = 0; k < 3; ++k)
      box_eps *= std::max({max_[k], std::abs(points.lo[k] - p_[k]), std::abs(points.hi[k] - p_[k])});
    if (box_eps > 1e-280 && box_eps < 1e280) box_eps_ = box_eps;  // else never decides
  }
  int operator()(const Vec3& s) const {
    const double sx = s.x - p_.x, sy = s.y - p_.y, sz = s.z - p_.z;
    const double det = m01_ * sz - m02_ * sy + m12_ * sx;
    if (det > box_eps_) return 1;
    if (det < -box_eps_) return -1;
    const double eps = 2 * 5.1107127829973299e-15 * std::max(max_[0], std::abs(sx)) *
                       std::max(max_[1], std::abs(sy)) * std::max(max_[2], std::abs(sz));
    if (eps > 1e-280 && eps < 1e280) {  // no underflow or overflow in the bound
      if (det > eps) return 1;
      if (det < -eps) return -1;
    }
    return plane_.side(s);
  }

 private:
  const Plane& plane_;
  Vec3 p_;
  double m01_, m02_, m12_;
  double max_[3];
  double box_eps_ = INFINITY;
};

/// One object's part ends that lie lowest and highest along each axis: real ends, so that the
/// exact side of any of them is that of an end of one of the object's parts. (Three axes: more
/// directions or fewer were slower; BENCHMARKS.md, "Decisions measured".)
struct ObjectExtremes {
  static constexpr int kEnds = 6;
  uint32_t object;
  Vec3 end[kEnds];  ///< [2 axis]: least along the axis, [2 axis + 1]: greatest
  /// From a part's ends, lowest and highest along each axis in the order of `end`.
  ObjectExtremes(uint32_t o, const Vec3 (&part)[kEnds]) : object(o) { std::copy(part, part + kEnds, end); }
  /// A part's ends, lowest and highest along each axis in the order of `end`.
  void add(const Vec3 (&part)[kEnds]) {
    for (int axis = 0; axis < 3; ++axis) {
      if (part[2 * axis][axis] < end[2 * axis][axis]) end[2 * axis] = part[2 * axis];
      if (part[2 * axis + 1][axis] > end[2 * axis + 1][axis]) end[2 * axis + 1] = part[2 * axis + 1];
    }
  }
};

struct Candidate {
  bool valid = false;
  Plane plane;
  double reduction = 0;
};

struct Evaluation {
  Candidate best;
  uint64_t axis = 0, geometry = 0, geometry_full = 0;
};

}  // namespace viewcells::subdivision_detail
