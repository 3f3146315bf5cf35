// Adaptive view space subdivision (view-cell-construction paper, section 4.2).
//
// Each node holds its segments as (id, t0, t1): the part of segment id inside the node. A
// segment goes to the negative child when part of it lies strictly on the negative side, to
// the positive child likewise, and to both when it lies in the plane (so it has length in both
// closed halves); a segment that only ends on the plane goes to one side. The same rule, in
// classify() below, decides candidate costs and actual splits, so the two always agree; for
// axis-aligned planes the sweep applies it through the segments' coordinate extents.
#include "viewcells/bsp/subdivision.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <queue>
#include <utility>

#include "bsp/segment_walk.h"
#include "viewcells/core/default_init.h"
#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells {

std::vector<int32_t> Subdivision::leaves() const { return leaves_after(splits.size()); }

std::vector<int32_t> Subdivision::leaves_after(size_t k) const {
  VC_CHECK(k <= splits.size());
  // After k splits the nodes are 0 .. 2k; a node is a leaf then unless split among the first k.
  std::vector<char> split_done(2 * k + 1, 0);
  for (size_t i = 0; i < k; ++i) split_done[splits[i].node] = 1;
  std::vector<int32_t> out;
  for (size_t n = 0; n <= 2 * k; ++n)
    if (!split_done[n]) out.push_back(static_cast<int32_t>(n));
  return out;
}

double Subdivision::cost() const {
  const double w = nodes[0].weight;
  double c = 0;
  for (int32_t n : leaves()) c += nodes[n].weight / w * nodes[n].pvs_cost;
  return c;
}

ConvexPolyhedron HeightBandDensity::band_part(const ConvexPolyhedron& cell) const {
  ConvexPolyhedron part = cell;
  const Box3 b = cell.bounds();
  if (b.hi.z <= lo || b.lo.z >= hi) return ConvexPolyhedron();
  if (b.lo.z < lo)
    if (auto halves = part.split(Plane::axis_aligned(2, lo), -1)) part = std::move(halves->second);
  if (b.hi.z > hi)
    if (auto halves = part.split(Plane::axis_aligned(2, hi), -1)) part = std::move(halves->first);
  return part;
}

double HeightBandDensity::weight(const ConvexPolyhedron& cell) const {
  const double v = cell.volume();
  if (!enabled) return v;
  const ConvexPolyhedron part = band_part(cell);
  const double in_band = part.empty() ? 0.0 : part.volume();
  return outside * (v - in_band) + in_band;
}

double HeightBandDensity::weight_below(const ConvexPolyhedron& cell, const ConvexPolyhedron& part,
                                       const Plane& plane) const {
  const double v = cell.volume_below(plane);
  if (!enabled) return v;
  const double in_band = part.empty() ? 0.0 : part.volume_below(plane);
  return outside * (v - in_band) + in_band;
}

int32_t Subdivision::locate(const Vec3& p) const {
  if (nodes.empty() || !view_box.contains(p)) return -1;
  int32_t n = 0;
  while (nodes[n].plane >= 0) n = nodes[n].child[planes[nodes[n].plane].side(p) > 0 ? 1 : 0];
  return n;
}

SplitStrategy parse_split_strategy(const std::string& name) {
  if (name == "av-s") return SplitStrategy::kCost;
  if (name == "kd-casm") return SplitStrategy::kKdCycling;
  if (name == "kd-lasm") return SplitStrategy::kKdLongest;
  if (name == "kd-vt") return SplitStrategy::kKdVisibility;
  if (name == "kd-vt-star") return SplitStrategy::kKdVisibilityDepthFirst;
  if (name == "bsp") return SplitStrategy::kPolygonBsp;
  throw Error("unknown subdivision method '" + name + "' (expected av-s, kd-casm, kd-lasm, kd-vt, kd-vt-star or bsp)");
}

const char* to_string(SplitStrategy s) {
  switch (s) {
    case SplitStrategy::kCost: return "av-s";
    case SplitStrategy::kKdCycling: return "kd-casm";
    case SplitStrategy::kKdLongest: return "kd-lasm";
    case SplitStrategy::kKdVisibility: return "kd-vt";
    case SplitStrategy::kKdVisibilityDepthFirst: return "kd-vt-star";
    case SplitStrategy::kPolygonBsp: return "bsp";
  }
  return "?";
}

bool use_geometry_aligned(const Scene& scene, const SubdivisionConfig& config, std::string& reason) {
  const double share = scene.non_axis_aligned_share();
  const std::string pct = std::to_string(static_cast<int>(std::round(100 * share))) + "%";
  switch (config.geometry_aligned) {
    case GeometryAlignedMode::kOn: reason = "enabled by the user (" + pct + " of the surface is not axis-aligned)"; return true;
    case GeometryAlignedMode::kOff: reason = "disabled by the user"; return false;
    case GeometryAlignedMode::kAuto: break;
  }
  if (share >= config.ga_auto_share) {
    reason = "enabled: " + pct + " of the surface area is not axis-aligned";
    return true;
  }
  reason = "disabled: only " + pct + " of the surface area is not axis-aligned (axis-aligned candidates cover it)";
  return false;
}

namespace {

/// A Subdivision as bsp_detail::walk_segment reads it.
struct SubdivisionTree {
  const Subdivision& s;
  int axis(int32_t n) const { return s.planes[s.nodes[n].plane].axis; }
  double offset(int32_t n) const { return s.planes[s.nodes[n].plane].offset; }
  const Plane& plane(int32_t n) const { return s.planes[s.nodes[n].plane]; }
  int32_t child(int32_t n, int k) const { return s.nodes[n].child[k]; }
};

template <class Stop>
void walk_segment(const Subdivision& s, const Vec3& a, const Vec3& b,
                  std::vector<std::tuple<int32_t, double, double>>& stack, Stop&& stop) {
  bsp_detail::walk_segment(SubdivisionTree{s}, a, b, stack, std::forward<Stop>(stop));
}

}  // namespace

void clip_to_leaves(const Subdivision& s, const ConvexPolyhedron& cell,
                    const std::function<void(int32_t, const ConvexPolyhedron&)>& at_leaf) {
  if (cell.empty() || s.nodes.empty()) return;
  std::vector<std::pair<int32_t, ConvexPolyhedron>> stack;
  stack.emplace_back(0, cell);
  while (!stack.empty()) {
    auto [n, part] = std::move(stack.back());
    stack.pop_back();
    const BspNode& bn = s.nodes[n];
    if (bn.plane < 0) {
      at_leaf(n, part);
      continue;
    }
    const Plane& plane = s.planes[bn.plane];
    auto halves = part.split(plane, bn.plane);
    if (halves) {
      stack.emplace_back(bn.child[0], std::move(halves->first));
      stack.emplace_back(bn.child[1], std::move(halves->second));
    } else {  // the plane does not cut the part: it lies on one side
      stack.emplace_back(bn.child[plane.side(part.centroid()) > 0 ? 1 : 0], std::move(part));
    }
  }
}

void Subdivision::leaves_of_segment(const Vec3& a, const Vec3& b, std::vector<int32_t>& out,
                                    std::vector<std::tuple<int32_t, double, double>>& stack) const {
  walk_segment(*this, a, b, stack, [&](int32_t n, double, double) {
    if (nodes[n].plane >= 0) return false;
    out.push_back(n);
    return true;
  });
}

void Subdivision::pieces_of_segment(const Vec3& a, const Vec3& b, std::vector<std::tuple<int32_t, double, double>>& out,
                                    std::vector<std::tuple<int32_t, double, double>>& stack) const {
  walk_segment(*this, a, b, stack, [&](int32_t n, double t0, double t1) {
    if (nodes[n].plane >= 0) return false;
    out.emplace_back(n, t0, t1);
    return true;
  });
}

namespace {

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
/// exact side of any of them is that of an end of one of the object's parts. (With the 4 body
/// diagonals of a cube too, 7 directions, the bound let through 7% fewer planes to a pass over
/// all parts, but oa_shouse's subdivision took 8% longer in alternating runs: 1.57-1.60 s
/// against 1.44-1.48 s; with the 6 face diagonals as well, longer still. With two axes, 33%
/// more passes and 1.52-1.57 s.)
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

class Builder {
 public:
  /// Nodes of at least this many parts evaluate their axes (and sort their positions) in
  /// parallel; smaller ones in one thread, their siblings beside them. The same results.
  static constexpr size_t kParallelParts = 1 << 13;
  /// best_axis_candidate in a cell that is not a box: one clip of the cell every kStride positions.
  static constexpr size_t kStride = 16;

  Builder(const Scene& scene, const SegmentSet& segs, const CostModel& model, const SubdivisionConfig& config,
          Subdivision& out)
      : scene_(scene),
        segs_(segs),
        model_(model),
        r_(per_object_costs(scene, model)),
        config_(config),
        out_(out),
        total_volume_(segs.view_box.volume()),
        ends_(segs.size()) {}

  void run() {
    const auto start = std::chrono::steady_clock::now();
    out_.view_box = segs_.view_box;
    points_ = static_cast<bool>(config_.viewpoints);
    if (config_.strategy == SplitStrategy::kCost) {
      out_.stats.geometry_aligned = use_geometry_aligned(scene_, config_, out_.stats.geometry_aligned_reason);
    } else {
      out_.stats.geometry_aligned_reason = std::string("not used by ") + to_string(config_.strategy);
    }
    ga_ = out_.stats.geometry_aligned;
    if (ga_) {
      plane_source_.assign(scene_.triangles.size(), 0);
      for (uint32_t t = 0; t < scene_.triangles.size(); ++t) plane_source_[t] = plane_direction(t).has_value();
    }
    if (!(total_volume_ > 0)) throw Error("the view space box has zero volume");
    const Box3& b = out_.view_box;
    for (int a = 0; a < 3; ++a) {
      out_.planes.push_back(Plane::axis_aligned(a, b.lo[a]));
      out_.planes.push_back(Plane::axis_aligned(a, b.hi[a]));
    }
    // Box faces: -x, +x, -y, +y, -z, +z match planes 0..5.
    ConvexPolyhedron root = ConvexPolyhedron::box(b, 0);
    RawVector<SegRef> refs(segs_.size());
    // The builder numbers the segments in the Z-order of their ends (coherent_order), and a
    // cell keeps its parts in that order: the parts of a cell, which lie near each other, then
    // read their ends (64 bytes a segment, 96 MB for the city's 1.5M) from nearby memory. In
    // the order they were sampled, every part's ends were a miss of its own (the city's
    // subdivision to 50k cells and oa_shouse's: 0.85x the time, A/B).
    order_ = coherent_order(segs_, segs_.view_box);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, static_cast<uint32_t>(segs_.size()), 1 << 14),
                      [&](const tbb::blocked_range<uint32_t>& range) {
                        for (uint32_t k = range.begin(); k < range.end(); ++k) {
                          const size_t i = order_[k];
                          ends_[k] = {segs_.a(i), segs_.b(i), segs_.object_a[i], segs_.object_b[i],
                                      triangle_of(segs_.triangle_a, i), triangle_of(segs_.triangle_b, i)};
                          refs[k] = {k, 0, SegRef::kOne};
                        }
                      });
    if (config_.strategy == SplitStrategy::kPolygonBsp) {
      // The polygons that reach into the view space.
      std::vector<uint32_t> inside;
      for (uint32_t t = 0; t < scene_.triangles.size(); ++t) {
        Box3 tb;
        for (uint32_t v : scene_.triangles[t]) tb.extend(scene_.vertices[v]);
        if (tb.lo.x <= b.hi.x && tb.hi.x >= b.lo.x && tb.lo.y <= b.hi.y && tb.hi.y >= b.lo.y && tb.lo.z <= b.hi.z &&
            tb.hi.z >= b.lo.z)
          inside.push_back(t);
      }
      tris_.push_back(std::move(inside));
    }
    add_node(-1, std::move(root), std::move(refs));
    if (points_) {
      // Weighted by the viewpoints in the box: together they weigh its volume.
      std::vector<uint32_t> inside;
      const std::vector<Vec3>& p = *config_.viewpoints;
      for (uint32_t i = 0; i < p.size(); ++i)
        if (b.contains(p[i])) inside.push_back(i);
      if (inside.empty()) throw Error("none of the " + std::to_string(p.size()) + " viewpoints lies in the view box");
      point_weight_ = total_volume_ / static_cast<double>(inside.size());
      out_.nodes[0].weight = total_volume_;
      pts_.push_back(std::move(inside));
    }
    total_weight_ = out_.nodes[0].weight;
    pvs_budget_ = config_.pvs_budget_share * out_.nodes[0].pvs_cost;
    if (!(total_weight_ > 0)) throw Error("the viewpoint density is zero everywhere in the view space");
    out_.initial_cost = node_cost(0);
    double cost = out_.initial_cost;

    using Entry = std::pair<double, int32_t>;  // priority, node
    auto lower = [](const Entry& x, const Entry& y) {
      return x.first < y.first || (x.first == y.first && x.second > y.second);  // ties: older node first
    };
    std::priority_queue<Entry, std::vector<Entry>, decltype(lower)> queue(lower);
    best_.resize(1);
    if (gathers_extents()) pending_ext_.push_back(std::make_unique<NodeExtents>(node_extents(refs_[0])));
    const Evaluation first = evaluate(0);
    best_[0] = first.best;
    count_evaluation(0, first);
    if (best_[0].valid) queue.push({priority(0), 0});

    Progress progress("subdividing", config_.max_cells);
    if (config_.show_progress) progress.advance(1);
    uint32_t stagnant = 0;
    // Splits in rounds. A round takes the first cells of the queue, divides their parts and
    // evaluates their children in parallel (each child under the id, and each new face under
    // the plane id, that it gets if the round's cells are split in the order taken), then
    // replays the serial order: a cell is split only while no child split off before it in
    // the round outranks it. From the first cell that one does, the rest of the round is undone
    // and goes back to the queue (rarely: 6 cells in 49,999 splits of the city, rounds of 16,
    // stats.splits_undone). What a cell's split and its children's evaluations give depends
    // only on the cell, its id and its plane's id, so the tree is the serial loop's, for any
    // round size and thread count.
    // Depth-first (KD-VT*) splits the newest cell first, so a child always outranks the next
    // cell of a round and every round but its first cell would be undone: one cell at a time.
    const size_t round_size =
        config_.strategy == SplitStrategy::kKdVisibilityDepthFirst ? 1 : static_cast<size_t>(config_.split_round);
    std::vector<PendingSplit> round;
    out_.stats.stop_reason = "reached the maximum number of cells";
    bool stopped = false;
    while (!stopped && out_.leaf_count() < config_.max_cells) {
      throw_if_interrupted("subdivision");
      if (queue.empty()) {
        out_.stats.stop_reason = config_.strategy == SplitStrategy::kCost
                                     ? "no cell can be split further (no candidate reduces the cost)"
                                     : "no cell is left to split under the method's own termination rule";
        break;
      }
      // The first cells of the queue, with their cells cut, up to the splits still wanted; the
      // planes of those that cut are added (the children's new faces name them) in this order.
      round.clear();
      size_t cuts = 0;
      while (!queue.empty() && round.size() < round_size && cuts < config_.max_cells - out_.leaf_count()) {
        PendingSplit& p = round.emplace_back();
        p.node = queue.top().second;
        queue.pop();
        p.cand = best_[p.node];
        p.plane_id = static_cast<int32_t>(out_.planes.size());
        p.halves = out_.cells[p.node].split(p.cand.plane, p.plane_id);
        // A sliver (its volume rounds to nothing or below) helps no one and breaks p(i) >= 0:
        // the cell stays whole. Candidates are filtered by the same relative size, but they
        // see estimated volumes; this is the exact check on the cells themselves.
        const double min_part = kMinPart * out_.nodes[p.node].volume;
        p.cuts = p.halves && p.halves->first.volume() > min_part && p.halves->second.volume() > min_part;
        cuts += p.cuts;
        if (p.cuts) out_.planes.push_back(p.cand.plane);  // the children's faces name it
      }
      tbb::parallel_for(size_t{0}, round.size(), [&](size_t i) {
        if (round[i].cuts) prepare_split(round[i]);
      });
      // Children under the ids they get in this order, then all evaluated at once.
      const size_t first_child = out_.nodes.size();
      for (PendingSplit& p : round)
        if (p.cuts) add_children(p);
      best_.resize(out_.nodes.size());
      std::vector<Evaluation> evaluations(out_.nodes.size() - first_child);
      tbb::parallel_for(size_t{0}, evaluations.size(), [&](size_t i) {
        const int32_t child = static_cast<int32_t>(first_child + i);
        evaluations[i] = evaluate(child);
        best_[child] = evaluations[i].best;
      });
      // The serial order, replayed.
      size_t done = 0, next_child = first_child;
      for (; done < round.size(); ++done) {
        const PendingSplit& p = round[done];
        if (!queue.empty() && lower({priority(p.node), p.node}, queue.top())) break;  // a child comes first
        stagnant = p.cand.reduction < config_.min_reduction * out_.initial_cost ? stagnant + 1 : 0;
        if (config_.strategy == SplitStrategy::kCost && stagnant >= config_.stagnation_steps) {
          out_.stats.stop_reason = "the cost reduction stayed below the threshold for " +
                                   std::to_string(config_.stagnation_steps) + " successive splits";
          stopped = true;
          break;
        }
        if (!p.cuts) {  // degenerate after all: the cell stays whole
          slivers_refused_ += p.halves.has_value();
          continue;
        }
        const double before = node_cost(p.node);
        commit_split(p, static_cast<int32_t>(next_child));
        const int32_t c0 = static_cast<int32_t>(next_child), c1 = c0 + 1;
        for (int32_t c : {c0, c1}) count_evaluation(c, evaluations[static_cast<size_t>(c) - first_child]);
        next_child += 2;
        const double after = node_cost(c0) + node_cost(c1);
        cost += after - before;
        out_.splits.push_back({p.node, before - after, cost});
        for (int32_t c : {c0, c1})
          if (best_[c].valid) queue.push({priority(c), c});
        if (config_.show_progress) progress.advance(1);
      }
      // The rest of the round: its children removed, its cells back in the queue (unless stopped).
      if (done < round.size()) {
        truncate_nodes(next_child);
        if (!stopped) {
          for (size_t i = done; i < round.size(); ++i) queue.push({priority(round[i].node), round[i].node});
          splits_undone_ += round.size() - done;
        }
      }
    }
    if (config_.show_progress) progress.finish();
    // Each leaf's parts freed as soon as its ids are copied, so that the ids reuse their memory
    // (at 50k cells the ids are 190 MB, the parts 570 MB).
    out_.segments.resize(out_.nodes.size());
    for (size_t n = 0; n < out_.nodes.size(); ++n) {
      if (out_.nodes[n].plane >= 0) continue;
      auto& ids = out_.segments[n];
      ids.reserve(refs_[n].size());
      for (const SegRef& s : refs_[n]) ids.push_back(static_cast<uint32_t>(order_[s.id]));  // the caller's ids
      RawVector<SegRef>().swap(refs_[n]);
    }
    out_.stats.axis_candidates = axis_evaluated_;
    out_.stats.parts_evaluated = parts_evaluated_;
    out_.stats.slivers_refused = slivers_refused_;
    out_.stats.splits_undone = splits_undone_;
    out_.stats.geometry_candidates = geometry_evaluated_;
    out_.stats.geometry_full_passes = geometry_full_;
    out_.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

 private:
  double node_cost(int32_t n) const { return out_.nodes[n].weight / total_weight_ * out_.nodes[n].pvs_cost; }
  double priority(int32_t n) const {
    switch (config_.strategy) {
      case SplitStrategy::kCost: return best_[n].reduction + 0.01 * node_cost(n);
      case SplitStrategy::kKdVisibilityDepthFirst: return n;  // newest first: depth-first
      default: return -static_cast<double>(n);                // oldest first: breadth-first
    }
  }

  double pvs_cost(const ConvexPolyhedron& cell, const RawVector<SegRef>& refs) {
    if (model_.pixel_term()) {
      double c = 0;
      for_each_cell_cost(cell, refs, [&](uint32_t, double r) { c += r; });
      return c;
    }
    Marks& m = marks_.local();
    m.reset(r_.size());
    double c = 0;
    for (size_t i = 0; i < refs.size(); ++i) {
      prefetch_ends(refs, i);
      const SegEnds& e = ends_[refs[i].id];
      c += m.add(e.object_a, r_.data()) + m.add(e.object_b, r_.data());
    }
    return c;
  }

  /// A node's parts name their segments in increasing but sparse order, which the hardware does
  /// not predict: the segment a few parts ahead is fetched while this one is used.
  void prefetch_ends(const RawVector<SegRef>& refs, size_t i) const {
    constexpr size_t kAhead = 48;
    if (i + kAhead < refs.size()) __builtin_prefetch(&ends_[refs[i + kAhead].id]);
  }

  /// With the pixel term: calls f(object, r(o) in this cell) once for every object the cell's
  /// segments see (pixels estimated from the cell's bounding box, cost_model.h).
  template <typename F>
  void for_each_cell_cost(const ConvexPolyhedron& cell, const RawVector<SegRef>& refs, F&& f) {
    const std::vector<Vec3> points = pixel_estimation_points(cell.bounds());
    Marks& m = marks_.local();
    m.reset(r_.size());
    for (const SegRef& s : refs)
      for (uint32_t o : {ends_[s.id].object_a, ends_[s.id].object_b})
        if (m.first(o)) f(o, cell_object_cost(scene_.objects[o], r_[o], points, model_));
  }

  /// The object costs candidate splits of `node` are evaluated with: the node's own (pixel
  /// term estimated from the node's points, used for both sides), else the global ones.
  /// Only the entries of objects the node's segments see are written.
  const double* candidate_costs(int32_t node, RawVector<double>& storage) {
    if (!model_.pixel_term()) return r_.data();
    storage.resize(r_.size());
    for_each_cell_cost(out_.cells[node], refs_[node], [&](uint32_t o, double r) { storage[o] = r; });
    return storage.data();
  }

  /// A node's volume, weight and r(PVS) (thread-safe: the two children are measured at once);
  /// r(PVS) from the node's extents when they are known and the costs are global.
  BspNode measure_node(int32_t parent, const ConvexPolyhedron& cell, const RawVector<SegRef>& refs,
                       const NodeExtents* ext) {
    BspNode node;
    node.parent = parent;
    node.volume = cell.volume();
    node.weight = config_.density.weight(cell);
    node.pvs_cost = ext && !model_.pixel_term() ? ext->pvs_cost(r_) : pvs_cost(cell, refs);
    return node;
  }

  int32_t add_node(int32_t parent, ConvexPolyhedron cell, RawVector<SegRef> refs) {
    const BspNode node = measure_node(parent, cell, refs, nullptr);
    return add_node(node, std::move(cell), std::move(refs));
  }

  int32_t add_node(const BspNode& node, ConvexPolyhedron cell, RawVector<SegRef> refs) {
    const int32_t parent = node.parent;
    depth_.push_back(parent < 0 ? 0 : depth_[parent] + 1);
    plane_hits_.push_back(1);  // until add_children knows better
    out_.nodes.push_back(node);
    out_.cells.push_back(std::move(cell));
    refs_.push_back(std::move(refs));
    return static_cast<int32_t>(out_.nodes.size() - 1);
  }

  /// A node's parts divided by a plane: each child's parts and, for AV-S, extents. It reads
  /// only the node's parts, so it can run beside other work (see run()).
  struct Partition {
    RawVector<SegRef> side[2];
    std::array<NodeExtents, 2> ext;
    bool plane_hits[2] = {false, false};  ///< with geometry-aligned planes: see plane_hits_
  };

  /// AV-S evaluates cells by their extents, which splits gather; the baselines need none.
  bool gathers_extents() const { return config_.strategy == SplitStrategy::kCost; }

  Partition partition(int32_t node, const Plane& plane) {
    const bool extents = gathers_extents();
    // Sides first (bit 0 negative, bit 1 positive, bit 2: crosses, the negative part first,
    // bit 3: crosses, the positive part first), with each child's extents (NodeExtents, which
    // its evaluation and r(PVS) need) gathered in the same pass; then both children written at
    // once. Both passes go chunk by chunk in parallel for large cells, each chunk at its own
    // offset and the extents joined in chunk order, so the result is the same for any threads.
    const RawVector<SegRef>& refs = refs_[node];
    const size_t n = refs.size();
    // Chunks of at least kGrain parts, a few per thread (the result does not depend on them).
    constexpr size_t kGrain = 1 << 16;
    const size_t threads = std::min<size_t>(
        static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency())),
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    const size_t chunks = std::clamp<size_t>((n + kGrain - 1) / kGrain, 1, threads == 1 ? 1 : 4 * threads);
    const size_t grain = (n + chunks - 1) / chunks;
    RawVector<uint8_t> code(n);
    // Per chunk, where its crossing parts are cut, in order (a few percent of the parts: an
    // array over all parts cost page faults on hundreds of megabytes over a run).
    std::vector<std::vector<uint32_t>> cuts(chunks);
    std::vector<std::array<size_t, 2>> at(chunks + 1, {0, 0});  // per chunk: its first index in each child
    std::array<std::vector<NodeExtents>, 2> chunk_ext;  // per side, per chunk
    std::vector<std::array<uint8_t, 2>> chunk_hits(chunks, {0, 0});  // per chunk: plane_hits of each side
    if (extents)
      for (auto& side_ext : chunk_ext) side_ext.resize(chunks);
    auto for_chunks = [&](auto&& f) {
      if (chunks == 1) return f(size_t{0});
      tbb::parallel_for(size_t{0}, chunks, [&](size_t c) { f(c); });
    };
    for_chunks([&](size_t c) {
      size_t count[2] = {0, 0};
      std::array<ExtentSlots, 2>& slots = split_slots_.local();
      if (extents)
        for (ExtentSlots& sl : slots) sl.reset(r_.size());
      uint8_t hits[2] = {0, 0};
      for (size_t i = c * grain; i < std::min(n, (c + 1) * grain); ++i) {
        prefetch_ends(refs, i);
        const SegRef& s = refs[i];
        const SegEnds& e = ends_[s.id];
        const double t0 = s.t0(), t1 = s.t1();
        const Vec3 p0 = e.at(t0), p1 = e.at(t1);
        const int s0 = plane.side(p0), s1 = plane.side(p1);
        int to = classify(s0, s1);
        if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
          // Crosses: each side gets its part (the cut point is rounded; sides stay exact).
          to |= s0 < 0 ? 4 : 8;
          const double d0 = plane.distance(p0), d1 = plane.distance(p1);
          const double cut = bsp_detail::cut_parameter(t0, t1, d0, d1);
          const uint32_t q = static_cast<uint32_t>(cut * 0x1p31);  // exact: cut is on the grid
          cuts[c].push_back(q);
          const int first = s0 < 0 ? 0 : 1;  // the child of the part before the cut
          if (ga_) {
            hits[first] |= hits_plane_source({s.id, s.q0, q}, e);
            hits[1 - first] |= hits_plane_source({s.id, q, s.q1}, e);
          }
          if (extents) {
            const Vec3 mid = e.at(cut);
            slots[first].add_part(p0, mid, e.object_a, e.object_b, chunk_ext[first][c]);
            slots[1 - first].add_part(mid, p1, e.object_a, e.object_b, chunk_ext[1 - first][c]);
          }
        } else {
          if (ga_ && hits_plane_source(s, e))
            for (int k = 0; k < 2; ++k) hits[k] |= (to >> k) & 1;
          if (extents)
            for (int k = 0; k < 2; ++k)
              if (to & (1 << k)) slots[k].add_part(p0, p1, e.object_a, e.object_b, chunk_ext[k][c]);
        }
        code[i] = static_cast<uint8_t>(to);
        count[0] += to & 1;
        count[1] += (to >> 1) & 1;
      }
      if (extents)
        for (int k = 0; k < 2; ++k) slots[k].finish(chunk_ext[k][c]);
      at[c + 1] = {count[0], count[1]};
      chunk_hits[c] = {hits[0], hits[1]};
    });
    Partition out;
    for (const auto& h : chunk_hits)
      for (int k = 0; k < 2; ++k) out.plane_hits[k] |= h[k] != 0;
    if (extents)
      for (int k = 0; k < 2; ++k) out.ext[k] = join_extents(chunk_ext[k]);
    for (size_t c = 0; c < chunks; ++c)
      for (int k = 0; k < 2; ++k) at[c + 1][k] += at[c][k];
    RawVector<SegRef>* side = out.side;
    side[0].resize(at[chunks][0]);
    side[1].resize(at[chunks][1]);
    for_chunks([&](size_t c) {
      size_t next[2] = {at[c][0], at[c][1]};
      const uint32_t* cut = cuts[c].data();
      for (size_t i = c * grain; i < std::min(n, (c + 1) * grain); ++i) {
        const SegRef& s = refs[i];
        if (code[i] & 12) {
          const uint32_t q = *cut++;
          const int first = (code[i] & 4) ? 0 : 1;
          side[first][next[first]++] = {s.id, s.q0, q};
          side[1 - first][next[1 - first]++] = {s.id, q, s.q1};
          continue;
        }
        if (code[i] & 1) side[0][next[0]++] = s;
        if (code[i] & 2) side[1][next[1]++] = s;
      }
    });
    return out;
  }

  /// A cell taken from the queue in a round of splits (see run()).
  struct PendingSplit {
    int32_t node = -1;
    Candidate cand;
    int32_t plane_id = -1;  ///< the id of its plane in out_.planes, if it cuts
    std::optional<std::pair<ConvexPolyhedron, ConvexPolyhedron>> halves;
    bool cuts = false;  ///< the plane cuts the cell into two parts, neither a sliver
    Partition parts;
    BspNode measured[2];
    std::vector<uint32_t> tri_side[2];  ///< the polygon BSP baseline: the polygons of each side
    std::vector<uint32_t> point_side[2];  ///< with viewpoints: those of each side
  };

  /// What splitting a cell by its plane gives, without changing any node: its parts divided
  /// and its children measured (and, for the polygon BSP, its polygons divided). Reads only
  /// the node, so the cells of a round are prepared at once.
  void prepare_split(PendingSplit& p) {
    const int32_t node = p.node;
    const Plane& plane = p.cand.plane;
    p.parts = partition(node, plane);
    if (config_.strategy == SplitStrategy::kPolygonBsp) {
      // Polygons go to the sides their vertices are on (both when cut); those lying in the
      // plane are used up.
      for (uint32_t t : tris_[node]) {
        bool neg = false, pos = false;
        for (uint32_t v : scene_.triangles[t]) {
          const int where = plane.side(scene_.vertices[v]);
          neg |= where < 0;
          pos |= where > 0;
        }
        if (neg) p.tri_side[0].push_back(t);
        if (pos) p.tri_side[1].push_back(t);
      }
    }
    const bool extents = gathers_extents();
    for (int k = 0; k < 2; ++k)
      p.measured[k] = measure_node(node, k == 0 ? p.halves->first : p.halves->second, p.parts.side[k],
                                   extents ? &p.parts.ext[k] : nullptr);
    if (points_) {
      const std::vector<Vec3>& at = *config_.viewpoints;
      for (uint32_t i : pts_[node]) p.point_side[plane.side(at[i]) > 0 ? 1 : 0].push_back(i);
      for (int k = 0; k < 2; ++k) p.measured[k].weight = static_cast<double>(p.point_side[k].size()) * point_weight_;
    }
  }

  /// Adds the two children of a prepared split as the next nodes (ids in the order added).
  void add_children(PendingSplit& p) {
    for (int k = 0; k < 2; ++k) {
      const int32_t c = add_node(p.measured[k], std::move(k == 0 ? p.halves->first : p.halves->second),
                                 std::move(p.parts.side[k]));
      plane_hits_[c] = p.parts.plane_hits[k];
      if (gathers_extents()) {
        pending_ext_.resize(out_.nodes.size());
        pending_ext_[c] = std::make_unique<NodeExtents>(std::move(p.parts.ext[k]));
      }
      if (config_.strategy == SplitStrategy::kPolygonBsp) tris_.push_back(std::move(p.tri_side[k]));
      if (points_) pts_.push_back(std::move(p.point_side[k]));
    }
  }

  /// Makes a prepared split part of the tree: its plane, and its children (ids c0, c0 + 1).
  void commit_split(const PendingSplit& p, int32_t c0) {
    const int32_t node = p.node;
    out_.nodes[node].plane = p.plane_id;
    refs_[node].clear();
    refs_[node].shrink_to_fit();
    if (config_.strategy == SplitStrategy::kPolygonBsp) tris_[node] = {};
    if (points_) pts_[node] = {};
    out_.cells[node] = ConvexPolyhedron();
    out_.nodes[node].child[0] = c0;
    out_.nodes[node].child[1] = c0 + 1;
  }

  /// Removes the nodes from id n on and the planes of uncommitted splits (the splits undone).
  void truncate_nodes(size_t n) {
    out_.planes.resize(6 + out_.splits.size());  // the view box's faces, then one per split
    out_.nodes.resize(n);
    out_.cells.resize(n);
    refs_.resize(n);
    depth_.resize(n);
    plane_hits_.resize(n);
    best_.resize(n);
    if (pending_ext_.size() > n) pending_ext_.resize(n);
    if (tris_.size() > n) tris_.resize(n);
    if (pts_.size() > n) pts_.resize(n);
  }

  /// Adds what evaluating a node of the tree took to the statistics (counted once the node is
  /// in the tree: evaluations of a round's undone children are not).
  void count_evaluation(int32_t node, const Evaluation& e) {
    axis_evaluated_ += e.axis;
    parts_evaluated_ += refs_[node].size();
    geometry_evaluated_ += e.geometry;
    geometry_full_ += e.geometry_full;
  }

  Evaluation evaluate(int32_t node) {
    Evaluation ev;
    switch (config_.strategy) {
      case SplitStrategy::kCost: break;
      case SplitStrategy::kPolygonBsp: ev.best = best_polygon_candidate(node, ev); return ev;
      default: ev.best = kd_candidate(node); ++ev.axis; return ev;
    }
    // The extents gathered when the node was split off (the root's when it was made).
    const std::unique_ptr<NodeExtents> ext = std::move(pending_ext_[node]);
    const RawVector<SegRef>& refs = refs_[node];
    if (refs.empty() || out_.nodes[node].pvs_cost == 0) return ev;
    RawVector<double> storage;
    const double* r = candidate_costs(node, storage);
    Candidate results[4];
    const std::array<std::vector<double>, 3> positions = axis_positions(node, out_.cells[node].bounds());
    auto task = [&](int t) { results[t] = best_axis_candidate(node, t, positions[t], *ext, ev, r); };
    // Small nodes in this thread (their sibling is evaluated beside them); the same results.
    if (refs.size() < kParallelParts) {
      for (int t = 0; t < 3; ++t) task(t);
    } else {
      tbb::parallel_for(0, 3, task);
    }
    // Geometry-aligned planes after the axes: one wins only by beating the best axis-aligned
    // candidate, so planes whose bound is below it need no exact evaluation.
    if (ga_) {
      double to_beat = -INFINITY;
      for (int t = 0; t < 3; ++t)
        if (results[t].valid) to_beat = std::max(to_beat, results[t].reduction);
      results[3] = best_geometry_candidate(node, ev, r, to_beat);
    }
    for (const Candidate& c : results)  // in a fixed order: ties keep the earlier kind/axis
      if (c.valid && (!ev.best.valid || c.reduction > ev.best.reduction)) ev.best = c;
    return ev;
  }

  /// The kd baselines: the spatial median of the cycling or the longest axis; KD-VT and KD-VT*
  /// leave cells under the PVS budget or at the maximum depth whole.
  Candidate kd_candidate(int32_t node) const {
    const SplitStrategy st = config_.strategy;
    if ((st == SplitStrategy::kKdVisibility || st == SplitStrategy::kKdVisibilityDepthFirst) &&
        (out_.nodes[node].pvs_cost <= pvs_budget_ || depth_[node] >= config_.max_depth))
      return {};
    const Box3 b = out_.cells[node].bounds();
    const Vec3 e = b.extent();
    int axis = depth_[node] % 3;
    if (st != SplitStrategy::kKdCycling) axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const double at = 0.5 * (b.lo[axis] + b.hi[axis]);
    if (!(at > b.lo[axis] && at < b.hi[axis])) return {};  // too thin to split in floating point
    return {true, Plane::axis_aligned(axis, at), 0.0};
  }

  /// The BSP baseline: among (a random subset of) the planes of the polygons in the cell, the
  /// one that cuts the fewest polygons and balances the sides best (score 8 * cut + |front -
  /// back|, a classic cell-and-portal heuristic). Sides are counted in floating point here;
  /// the split itself uses exact predicates.
  Candidate best_polygon_candidate(int32_t node, Evaluation& ev) {
    const std::vector<uint32_t>& tris = tris_[node];
    if (tris.empty()) return {};
    std::vector<uint32_t> pick = tris;
    if (pick.size() > config_.polygon_candidates) {
      Rng rng(config_.seed, (static_cast<uint64_t>(node) << 2) | 3);
      for (size_t i = 0; i < config_.polygon_candidates; ++i) std::swap(pick[i], pick[i + rng.below(pick.size() - i)]);
      pick.resize(config_.polygon_candidates);
    }
    const ConvexPolyhedron& cell = out_.cells[node];
    const double volume = out_.nodes[node].volume;
    const double eps = 1e-9 * out_.view_box.diagonal();
    Candidate best;
    double best_score = INFINITY;
    for (uint32_t t : pick) {
      const auto& tri = scene_.triangles[t];
      const Plane plane = Plane::through(scene_.vertices[tri[0]], scene_.vertices[tri[1]], scene_.vertices[tri[2]]);
      const double vl = cell.volume_below(plane);
      if (!(vl > 1e-9 * volume && volume - vl > 1e-9 * volume)) continue;  // does not cut the cell
      size_t front = 0, back = 0, cut = 0;
      for (uint32_t u : tris) {
        bool neg = false, pos = false;
        for (uint32_t v : scene_.triangles[u]) {
          const double d = plane.distance(scene_.vertices[v]);
          neg |= d < -eps;
          pos |= d > eps;
        }
        cut += neg && pos;
        front += pos && !neg;
        back += neg && !pos;
      }
      const double score = 8.0 * cut + std::abs(static_cast<double>(front) - static_cast<double>(back));
      if (score < best_score) {
        best_score = score;
        best = {true, plane, 0.0};
      }
    }
    __atomic_add_fetch(&ev.geometry, pick.size(), __ATOMIC_RELAXED);
    return best;
  }

  /// The axis-aligned positions tried in `node` along each axis (sorted, distinct, strictly
  /// inside the cell's bounds): all segment ends when there are at most max_axis_candidates,
  /// else a random choice, reproducible per node (SubdivisionConfig::exact_candidates).
  ///
  /// The random choice draws parts of the node at random (reproducibly per node) and takes
  /// both ends of each, along every axis that still needs positions, until each has k distinct
  /// ones or 2k parts are drawn (walls, where many segments end, repeat); each part drawn (a
  /// cache miss for its segment) serves the three axes, where drawing an end per axis cost two
  /// dependent misses per position. (A run of consecutive parts from a random one served
  /// until the parts were kept in the Z-order of their segments: a run is now one corner of
  /// the cell.)
  std::array<std::vector<double>, 3> axis_positions(int32_t node, const Box3& bounds) const {
    const RawVector<SegRef>& refs = refs_[node];
    const size_t k = config_.max_axis_candidates;
    const size_t n = refs.size();
    std::array<std::vector<double>, 3> positions;
    if (config_.exact_candidates || 2 * n <= 4 * k) {
      // Each axis sorts all the node's ends: the three at once in a large node.
      auto axis_task = [&](int axis) { positions[axis] = all_axis_positions(node, axis, bounds); };
      if (n < kParallelParts) {
        for (int axis = 0; axis < 3; ++axis) axis_task(axis);
      } else {
        tbb::parallel_for(0, 3, axis_task);
      }
      return positions;
    }
    Rng rng(config_.seed, static_cast<uint64_t>(node) << 2);
    std::vector<uint32_t> pick(2 * k);
    for (uint32_t& i : pick) i = static_cast<uint32_t>(rng.below(n));
    std::array<DrawnSet, 3>& drawn = drawn_.local();
    for (int axis = 0; axis < 3; ++axis) {
      drawn[axis].reset(k);
      positions[axis].reserve(k);
    }
    constexpr size_t kAhead = 16;
    for (size_t read = 0; read < 2 * k; ++read) {
      if (read + kAhead < 2 * k) __builtin_prefetch(&ends_[refs[pick[read + kAhead]].id]);
      const SegRef& part = refs[pick[read]];
      const SegEnds& e = ends_[part.id];
      const Vec3 p0 = e.at(part.t0()), p1 = e.at(part.t1());
      bool wanted = false;
      for (int axis = 0; axis < 3; ++axis) {
        std::vector<double>& at = positions[axis];
        for (double c : {p0[axis], p1[axis]})
          if (at.size() < k && c > bounds.lo[axis] && c < bounds.hi[axis] && drawn[axis].insert(c)) at.push_back(c);
        wanted |= at.size() < k;
      }
      if (!wanted) break;
    }
    for (std::vector<double>& at : positions) std::sort(at.begin(), at.end());
    return positions;
  }

  /// Every segment end of the node along `axis` strictly inside the bounds, sorted and
  /// distinct; a uniform random subset of k of them when there are more (paper, section 4.2).
  std::vector<double> all_axis_positions(int32_t node, int axis, const Box3& bounds) const {
    const RawVector<SegRef>& refs = refs_[node];
    const size_t k = config_.max_axis_candidates;
    const double lo_b = bounds.lo[axis], hi_b = bounds.hi[axis];
    Rng rng(config_.seed, (static_cast<uint64_t>(node) << 2) | static_cast<uint64_t>(axis));
    std::vector<double> positions;
    positions.reserve(2 * refs.size());
    for (size_t i = 0; i < refs.size(); ++i) {
      prefetch_ends(refs, i);
      const SegEnds& e = ends_[refs[i].id];
      for (double c : {e.at(refs[i].t0())[axis], e.at(refs[i].t1())[axis]})
        if (c > lo_b && c < hi_b) positions.push_back(c);
    }
    std::sort(positions.begin(), positions.end());
    positions.erase(std::unique(positions.begin(), positions.end()), positions.end());
    if (positions.size() > k) {
      for (size_t i = 0; i < k; ++i) std::swap(positions[i], positions[i + rng.below(positions.size() - i)]);
      positions.resize(k);
      std::sort(positions.begin(), positions.end());
    }
    return positions;
  }

  /// r(PVS) of both sides of the planes at the sorted positions x[0..k-1] along `axis`. A
  /// segment part [lo, hi] is on the negative side at x when lo < x (or it lies in the plane,
  /// lo == hi == x), on the positive side when hi > x (or lies in it): from the first position
  /// index jl on, up to the last index jr. An object is on the negative side from the smallest
  /// jl of its parts on, on the positive side up to the largest jr, which its lowest low end
  /// and highest high end give (NodeExtents); a histogram of those indices and prefix sums give
  /// both sides' costs at every position in O(objects log k + k).
  void side_costs(const NodeExtents& ext, int axis, const std::vector<double>& x, const double* r,
                  std::vector<double>& left, std::vector<double>& right) {
    const size_t k = x.size();
    PointMarks& m = point_marks_.local();
    // Branch-free binary searches over x padded with +inf to a power of two: the count of
    // positions below v (lower bound) or at most v (upper bound).
    size_t p = 1;
    while (p < k + 1) p *= 2;
    std::vector<double>& xs = m.padded;
    xs.assign(p, INFINITY);
    std::copy(x.begin(), x.end(), xs.begin());
    const double* xp = xs.data();
    auto below = [xp, p](double v) {
      size_t i = 0;
      for (size_t step = p / 2; step > 0; step /= 2) i += xp[i + step - 1] < v ? step : 0;
      return static_cast<int32_t>(i);
    };
    auto at_most = [xp, p](double v) {
      size_t i = 0;
      for (size_t step = p / 2; step > 0; step /= 2) i += xp[i + step - 1] <= v ? step : 0;
      return static_cast<int32_t>(i);
    };
    // A point along the axis is on both sides at a position equal to its coordinate.
    const std::vector<PointPart>& points = ext.points[axis];
    if (!points.empty()) {
      m.reset(r_.size());
      for (const PointPart& e : points) {
        const int32_t jl = below(e.at), jr = at_most(e.at) - 1;
        m.touch(e.object_a, jl, jr);
        m.touch(e.object_b, jl, jr);
      }
    }
    std::vector<double> from(k + 1, 0.0), upto(k + 1, 0.0);
    const int32_t none = static_cast<int32_t>(k);
    for (size_t i = 0; i < ext.objects.size(); ++i) {
      const uint32_t o = ext.objects[i];
      const double lo = ext.ranges[i].lo[axis], hi = ext.ranges[i].hi[axis];
      int32_t first = lo == INFINITY ? none : at_most(lo);  // index k: never on the negative side
      int32_t last = below(hi) - 1;                           // -1: never on the positive side
      if (!points.empty() && m.stamp[o] == m.epoch) {
        first = std::min(first, m.first[o]);
        last = std::max(last, m.last[o]);
      }
      from[first] += r[o];
      upto[static_cast<size_t>(last + 1)] += r[o];
    }
    left.assign(k, 0.0);
    right.assign(k, 0.0);
    double cost = 0;
    for (size_t j = 0; j < k; ++j) left[j] = cost += from[j];
    cost = 0;
    for (size_t j = k; j-- > 0;) right[j] = cost += upto[j + 1];
  }

  /// The node's parts' extents per object (NodeExtents), in one pass over its parts (in
  /// parallel chunks for large nodes, merged in order, so the result is the same).
  /// The extents of consecutive chunks of parts joined in chunk order (the first moved).
  NodeExtents join_extents(std::vector<NodeExtents>& chunks) {
    if (chunks.size() == 1) return std::move(chunks[0]);
    NodeExtents all;
    ExtentSlots& slots = extent_slots_.local();
    slots.reset(r_.size());
    for (const NodeExtents& c : chunks) slots.merge(c, all);
    slots.finish(all);
    return all;
  }

  NodeExtents node_extents(const RawVector<SegRef>& refs) {
    auto fill = [&](size_t begin, size_t end, NodeExtents& into) {
      ExtentSlots& slots = extent_slots_.local();
      slots.reset(r_.size());
      for (size_t i = begin; i < end; ++i) {
        prefetch_ends(refs, i);
        const SegRef& s = refs[i];
        const SegEnds& e = ends_[s.id];
        slots.add_part(e.at(s.t0()), e.at(s.t1()), e.object_a, e.object_b, into);
      }
      slots.finish(into);
    };
    constexpr size_t kGrain = 1 << 15;
    std::vector<NodeExtents> chunks(std::max<size_t>(1, (refs.size() + kGrain - 1) / kGrain));
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t c) {
      fill(c * kGrain, std::min(refs.size(), (c + 1) * kGrain), chunks[c]);
    });
    return join_extents(chunks);
  }

  /// The best axis-aligned split of `node` along `axis` among its candidate positions.
  Candidate best_axis_candidate(int32_t node, int axis, const std::vector<double>& positions, const NodeExtents& ext,
                                Evaluation& ev, const double* r) {
    const ConvexPolyhedron& cell = out_.cells[node];
    const Box3 bounds = cell.bounds();
    const double lo_b = bounds.lo[axis], hi_b = bounds.hi[axis];
    if (positions.empty()) return {};
    const size_t k = positions.size();
    std::vector<double> left, right;
    side_costs(ext, axis, positions, r, left, right);
    const double own = node_cost(node);
    const double volume = out_.nodes[node].volume, weight = out_.nodes[node].weight;
    const HeightBandDensity& density = config_.density;
    const bool box = cell.is_box(out_.planes);
    // Boxes: weights are linear along x and y, and piecewise linear along z.
    auto box_weight_below = [&](double x) {
      const double frac = (x - lo_b) / (hi_b - lo_b);
      if (!density.enabled || axis != 2) return weight * frac;
      const double area = volume / (hi_b - lo_b);
      const double in_band = std::max(0.0, std::min(x, density.hi) - std::max(lo_b, density.lo));
      return area * (density.outside * ((x - lo_b) - in_band) + in_band);
    };
    const ConvexPolyhedron part = (!box && density.enabled) ? density.band_part(cell) : ConvexPolyhedron();
    // With viewpoints, the weight below each position from the node's points: a point is
    // below every position at or above it (the positions are sorted).
    std::vector<double> points_below;
    if (points_) {
      std::vector<uint32_t> first_at(k + 1, 0);
      const std::vector<Vec3>& at = *config_.viewpoints;
      for (uint32_t i : pts_[node])
        ++first_at[std::lower_bound(positions.begin(), positions.end(), at[i][axis]) - positions.begin()];
      points_below.resize(k);
      uint64_t below = 0;
      for (size_t j = 0; j < k; ++j) points_below[j] = static_cast<double>(below += first_at[j]) * point_weight_;
    }
    auto volume_below = [&](size_t j) {
      return box ? volume * (positions[j] - lo_b) / (hi_b - lo_b)
                 : cell.volume_below(Plane::axis_aligned(axis, positions[j]));
    };
    auto reduction_at = [&](size_t j, double wl) {
      const double wr = weight - wl;
      return own - (wl * left[j] + wr * right[j]) / total_weight_;
    };
    // The first position of the highest reduction among those that leave no sliver. In a cell
    // that is not a box each volume below is a clip of the cell (a map's cells below a
    // geometry-aligned split: hundreds of thousands of clips), so it is computed only where
    // it can change the choice:
    // - with viewpoints, the reduction does not depend on it: only for a position that would
    //   become the best, to check that it leaves no sliver;
    // - with the volume as the weight, the reduction is linear in it and the volume below grows
    //   with the position: the volumes at every kStride-th position (anchors) bound those
    //   between, and a position whose bound stays below the best anchor's reduction (by more
    //   than rounding) cannot be the best.
    // The same choice as clipping at every position.
    bool found = false;
    size_t best_j = 0;
    double best_reduction = 0;
    auto consider = [&](size_t j, double vl, double wl) {
      if (!(vl > kMinPart * volume && volume - vl > kMinPart * volume)) return;
      const double reduction = reduction_at(j, wl);
      if (!found || reduction > best_reduction) {
        found = true;
        best_j = j;
        best_reduction = reduction;
      }
    };
    if (!box && points_ && !config_.clip_every_position) {
      for (size_t j = 0; j < k; ++j)
        if (!found || reduction_at(j, points_below[j]) > best_reduction) consider(j, volume_below(j), points_below[j]);
    } else if (!box && !density.enabled && k > 2 * kStride && !config_.clip_every_position) {
      std::vector<double> anchor_vl;  // at positions 0, kStride, 2 kStride, ... and k - 1
      double best_anchor = -INFINITY;
      for (size_t j = 0;; j = std::min(j + kStride, k - 1)) {
        const double vl = volume_below(j);
        anchor_vl.push_back(vl);
        if (vl > kMinPart * volume && volume - vl > kMinPart * volume)
          best_anchor = std::max(best_anchor, reduction_at(j, vl));
        if (j == k - 1) break;
      }
      const double margin = 1e-9 * std::abs(own) + 1e-300, slack = 1e-6 * volume;
      for (size_t j = 0; j < k; ++j) {
        const size_t a = j / kStride;
        if (j % kStride == 0 || j == k - 1) {
          const double vl = anchor_vl[j == k - 1 ? anchor_vl.size() - 1 : a];
          consider(j, vl, vl);
          continue;
        }
        const double lo = anchor_vl[a] - slack, hi = anchor_vl[a + 1] + slack;
        if (std::max(reduction_at(j, lo), reduction_at(j, hi)) < best_anchor - margin) continue;
        const double vl = volume_below(j);
        consider(j, vl, vl);
      }
    } else {
      for (size_t j = 0; j < k; ++j) {
        const double vl = volume_below(j);
        // Without a density the weight below is the volume below, just computed (weight_below
        // would clip the cell again for the same number).
        consider(j, vl,
                 points_           ? points_below[j]
                 : box             ? box_weight_below(positions[j])
                 : density.enabled ? density.weight_below(cell, part, Plane::axis_aligned(axis, positions[j]))
                                   : vl);
      }
    }
    __atomic_add_fetch(&ev.axis, k, __ATOMIC_RELAXED);
    if (!found) return {};
    return {true, Plane::axis_aligned(axis, positions[best_j]), best_reduction};
  }

  /// The unit normal of triangle t if its plane is a geometry-aligned candidate (not
  /// degenerate, not axis-aligned).
  std::optional<Vec3> plane_direction(uint32_t t) const {
    const Vec3 n = scene_.triangle_normal(t);
    const double len = length(n);
    if (!(len > 0)) return std::nullopt;
    const Vec3 u = n / len;
    if (std::max({std::abs(u.x), std::abs(u.y), std::abs(u.z)}) > 1.0 - 1e-9) return std::nullopt;
    return u;
  }

  /// Whether a node part's end inside the node hit a plane source (the triangles
  /// best_geometry_candidate takes its planes from).
  bool hits_plane_source(const SegRef& s, const SegEnds& e) const {
    return (s.q0 == 0 && e.triangle_a != kNoObject && plane_source_[e.triangle_a]) ||
           (s.q1 == SegRef::kOne && e.triangle_b != kNoObject && plane_source_[e.triangle_b]);
  }

  /// The best of the planes of non-axis-aligned triangles hit inside the node (a random subset;
  /// each costs O(n)), or none. In a large cell, only the planes whose bound may beat `to_beat`
  /// (the best axis-aligned reduction: ties keep the axis) are evaluated on all parts, so a
  /// plane left out could not have been chosen.
  Candidate best_geometry_candidate(int32_t node, Evaluation& ev, const double* r, double to_beat) {
    // About half the cells of oa_shouse hold no end on a plane source: no pass over their parts.
    if (!plane_hits_[node]) return {};
    const RawVector<SegRef>& refs = refs_[node];
    // Triangles hit at segment ends inside this node lie (at least partly) inside it.
    // (Distinct ones first, by marks; then sorted: far fewer than the parts.) The same pass
    // takes, in a cell of at most kBoundedParts parts, the parts' end points and objects, in
    // order, for all the planes' passes; in a larger one, each object's extreme part ends, from
    // which the planes are bounded (below). A large cell's parts are not kept: only about one of
    // its planes in 25 is then evaluated on all of them (oa_shouse: 1,251 of 31,732), and
    // that pass reads them again from the segments. (Kept, and the extremes taken in a pass of
    // their own, the map's subdivision took 0.91 s against 0.87 s by medians of seven
    // alternating runs: scripts/bench-ab-subdivision.sh 93e71b1 7 map:oa_shouse.)
    constexpr size_t kBoundedParts = 2048;
    const bool large = refs.size() > kBoundedParts;
    struct PartEnds {
      Vec3 p0, p1;
      uint32_t object_a, object_b;
    };
    std::vector<PartEnds> parts;
    std::vector<ObjectExtremes> extremes;  // large cells: per object of the cell
    if (!large) parts.resize(refs.size());
    Box3 points;
    std::vector<uint32_t> tris;
    Marks& seen = triangle_marks_.local();
    seen.reset(scene_.triangles.size());
    // Object -> its entry in extremes; this thread's, left all UINT32_MAX again after use.
    std::vector<uint32_t>& entry = extreme_entry_.local();
    if (large && entry.size() < r_.size()) entry.assign(r_.size(), UINT32_MAX);
    // A part's ends lowest and highest along each axis (p0 on a tie), which update its objects'
    // extremes as p0 and then p1 would.
    Vec3 part_ends[ObjectExtremes::kEnds];
    auto extend = [&](uint32_t o) {
      if (o == kNoObject) return;
      uint32_t& at = entry[o];
      if (at != UINT32_MAX) {
        extremes[at].add(part_ends);
        return;
      }
      at = static_cast<uint32_t>(extremes.size());
      extremes.emplace_back(o, part_ends);
    };
    for (size_t i = 0; i < refs.size(); ++i) {
      prefetch_ends(refs, i);
      const SegRef& s = refs[i];
      const SegEnds& e = ends_[s.id];
      if (s.q0 == 0 && seen.first(e.triangle_a)) tris.push_back(e.triangle_a);
      if (s.q1 == SegRef::kOne && seen.first(e.triangle_b)) tris.push_back(e.triangle_b);
      const Vec3 p0 = e.at(s.t0()), p1 = e.at(s.t1());
      points.extend(p0);
      points.extend(p1);
      if (large) {
        for (int axis = 0; axis < 3; ++axis) {
          part_ends[2 * axis] = p1[axis] < p0[axis] ? p1 : p0;
          part_ends[2 * axis + 1] = p1[axis] > p0[axis] ? p1 : p0;
        }
        extend(e.object_a);
        if (e.object_b != e.object_a) extend(e.object_b);
      } else {
        parts[i] = {p0, p1, e.object_a, e.object_b};
      }
    }
    for (const ObjectExtremes& x : extremes) entry[x.object] = UINT32_MAX;
    std::sort(tris.begin(), tris.end());
    // One candidate per distinct plane (walls are made of several triangles).
    std::map<std::array<long long, 4>, uint32_t> by_plane;
    for (uint32_t t : tris) {
      const std::optional<Vec3> direction = plane_direction(t);
      if (!direction) continue;
      const Vec3& u = *direction;
      const double d = dot(u, scene_.vertices[scene_.triangles[t][0]]);
      const double q = 1e6 / std::max(1.0, out_.view_box.diagonal());
      by_plane.emplace(std::array<long long, 4>{std::llround(u.x * 1e6), std::llround(u.y * 1e6),
                                                std::llround(u.z * 1e6), std::llround(d * q)},
                       t);
    }
    std::vector<uint32_t> planes;
    for (const auto& [key, t] : by_plane) planes.push_back(t);
    if (planes.empty()) return {};
    if (planes.size() > config_.ga_candidates) {
      Rng rng(config_.seed, (static_cast<uint64_t>(node) << 2) | 3);
      for (size_t i = 0; i < config_.ga_candidates; ++i)
        std::swap(planes[i], planes[i + rng.below(planes.size() - i)]);
      planes.resize(config_.ga_candidates);
    }
    const double own = node_cost(node);
    const double volume = out_.nodes[node].volume, weight = out_.nodes[node].weight;
    const ConvexPolyhedron& cell = out_.cells[node];
    const ConvexPolyhedron part = config_.density.enabled ? config_.density.band_part(cell) : ConvexPolyhedron();
    // The weight below a plane: the viewpoints on its negative side (each by the exact side, its
    // filter bounded by their box), or its volume below (or in the density's band).
    Box3 viewpoint_box;
    if (points_)
      for (uint32_t i : pts_[node]) viewpoint_box.extend((*config_.viewpoints)[i]);
    auto weight_below = [&](const Plane& plane, double vl) {
      if (points_) {
        const FilteredSide side(plane, viewpoint_box);
        uint64_t below = 0;
        for (uint32_t i : pts_[node]) below += side((*config_.viewpoints)[i]) <= 0;
        return static_cast<double>(below) * point_weight_;
      }
      if (config_.density.enabled) return config_.density.weight_below(cell, part, plane);
      return vl;
    };
    // What each side of a plane sees, r(PVS) summed: exact from all the parts (each plane costs
    // O(n)), or from below by the extremes: an object one of whose extreme part ends lies strictly
    // on a side is seen from there (that end's part touches the side), so those objects are a
    // subset of what each side sees, each side's r(PVS) can only grow from theirs, and the
    // reduction can only fall.
    auto side_costs = [&](const Plane& plane, bool from_extremes) {
      const FilteredSide side(plane, points);
      // Plain references, not a structured binding: clang 14 (the fuzz and sanitizer builds)
      // refuses bindings captured by the lambdas below.
      std::pair<Marks, Marks>& sides = side_pair_marks_.local();
      Marks& neg = sides.first;
      Marks& pos = sides.second;
      neg.reset(r_.size());
      pos.reset(r_.size());
      double cl = 0, cr = 0;
      if (from_extremes) {
        for (const ObjectExtremes& x : extremes) {
          bool on_neg = false, on_pos = false;
          for (int k = 0; k < ObjectExtremes::kEnds && !(on_neg && on_pos); ++k) {
            const int at = side(x.end[k]);
            on_neg |= at < 0;
            on_pos |= at > 0;
          }
          if (on_neg) cl += neg.add(x.object, r);
          if (on_pos) cr += pos.add(x.object, r);
        }
      } else {
        // A part whose objects both sides have seen adds nothing: its sides are not needed.
        auto add = [&](const Vec3& p0, const Vec3& p1, uint32_t a, uint32_t b) {
          const int to = classify(side(p0), side(p1));
          if (to & 1) cl += neg.add(a, r) + neg.add(b, r);
          if (to & 2) cr += pos.add(a, r) + pos.add(b, r);
        };
        auto known = [&](uint32_t a, uint32_t b) { return neg.seen(a) && neg.seen(b) && pos.seen(a) && pos.seen(b); };
        if (large) {
          for (size_t i = 0; i < refs.size(); ++i) {
            prefetch_ends(refs, i);
            const SegRef& s = refs[i];
            const SegEnds& e = ends_[s.id];
            if (known(e.object_a, e.object_b)) continue;
            add(e.at(s.t0()), e.at(s.t1()), e.object_a, e.object_b);
          }
        } else {
          for (const PartEnds& e : parts)
            if (!known(e.object_a, e.object_b)) add(e.p0, e.p1, e.object_a, e.object_b);
        }
      }
      return std::pair{cl, cr};
    };
    auto reduction = [&](double wl, std::pair<double, double> costs) {
      return own - (wl * costs.first + (weight - wl) * costs.second) / total_weight_;
    };
    // In a cell of more than kBoundedParts parts, every plane is first bounded from its
    // objects' extreme ends (O(objects), where most objects are seen across much of the cell),
    // then evaluated on all parts in the order of the bounds until the next bound is below the
    // best exact reduction (with a margin for rounding): the same choice as evaluating them all.
    // On oa_shouse about one plane in 25 is then evaluated on all parts. (Bounds from 512
    // evenly spaced parts, used before, missed so many objects on each side that nearly every
    // plane was evaluated on all parts.)
    const bool bounded = large && planes.size() > 1;
    // The planes in parallel, the best chosen in their order: ties keep the first.
    const double margin = 1e-9 * std::abs(own) + 1e-300;  // for rounding
    std::vector<Candidate> results(planes.size());
    std::vector<double> below(planes.size());  // each plane's weight below, for its exact pass
    tbb::parallel_for(size_t{0}, planes.size(), [&](size_t j) {
      const auto& tri = scene_.triangles[planes[j]];
      const Plane plane = Plane::through(scene_.vertices[tri[0]], scene_.vertices[tri[1]], scene_.vertices[tri[2]]);
      const double vl = cell.volume_below(plane), vr = volume - vl;
      if (!(vl > kMinPart * volume && vr > kMinPart * volume)) return;
      const auto costs = side_costs(plane, bounded);
      if (bounded) {
        // Whatever the weight below (0 to the cell's), the reduction is at most this. A plane
        // it leaves below the axis split (by more than rounding) cannot be chosen, and its
        // weight below, a pass over the cell's viewpoints with a viewpoint density, is not needed.
        const double any_weight = own - weight * std::min(costs.first, costs.second) / total_weight_;
        if (any_weight < to_beat - 2 * margin) return;
      }
      below[j] = weight_below(plane, vl);
      results[j] = {true, plane, reduction(below[j], costs)};
    });
    if (bounded) {
      std::vector<size_t> order;
      for (size_t j = 0; j < results.size(); ++j)
        if (results[j].valid) order.push_back(j);
      std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        return results[a].reduction > results[b].reduction || (results[a].reduction == results[b].reduction && a < b);
      });
      std::vector<char> exact(results.size(), 0);
      double best_exact = to_beat;
      for (size_t next = 0; next < order.size();) {
        if (results[order[next]].reduction < best_exact - margin) break;  // no later plane can win
        // A batch of planes with the highest bounds, evaluated on all parts in parallel.
        const size_t batch = std::min(order.size(), next + 4);
        tbb::parallel_for(next, batch, [&](size_t i) {
          Candidate& c = results[order[i]];
          c.reduction = reduction(below[order[i]], side_costs(c.plane, false));
        });
        for (; next < batch; ++next) {
          exact[order[next]] = 1;
          best_exact = std::max(best_exact, results[order[next]].reduction);
        }
      }
      for (size_t j = 0; j < results.size(); ++j)
        if (!exact[j]) results[j].valid = false;  // bounded below the best: cannot be chosen
    }
    // The planes still valid are those evaluated on all parts.
    __atomic_add_fetch(&ev.geometry_full,
                       static_cast<uint64_t>(std::count_if(results.begin(), results.end(),
                                                           [](const Candidate& c) { return c.valid; })),
                       __ATOMIC_RELAXED);
    Candidate best;
    for (const Candidate& c : results)
      if (c.valid && (!best.valid || c.reduction > best.reduction)) best = c;
    __atomic_add_fetch(&ev.geometry, planes.size(), __ATOMIC_RELAXED);
    return best;
  }

  const Scene& scene_;
  const SegmentSet& segs_;
  const CostModel& model_;
  const std::vector<double> r_;  ///< max(a, b t_o) per object
  const SubdivisionConfig& config_;
  Subdivision& out_;
  double total_volume_;
  double total_weight_ = 0;
  bool ga_ = false;
  std::vector<RawVector<SegRef>> refs_;
  std::vector<SegEnds> ends_;  ///< per segment, in the builder's order (order_)
  std::vector<size_t> order_;  ///< the builder's segment k is segs_'s order_[k]
  std::vector<uint32_t> depth_;              ///< per node
  /// With geometry-aligned planes: per triangle, whether it is a plane source (plane_direction);
  /// per node, whether one of its parts has an end inside it on a plane source (0: the node
  /// has no geometry-aligned candidates; the root and nodes not made by partition: 1).
  std::vector<uint8_t> plane_source_, plane_hits_;
  std::vector<std::vector<uint32_t>> tris_;  ///< BSP baseline: per node, the polygons in it
  /// With viewpoints (points_): per node, the viewpoints in it (those of split nodes freed),
  /// and the weight of one.
  std::vector<std::vector<uint32_t>> pts_;
  bool points_ = false;
  double point_weight_ = 0;
  double pvs_budget_ = 0;
  uint64_t slivers_refused_ = 0;
  uint64_t splits_undone_ = 0;
  std::vector<Candidate> best_;
  std::atomic<uint64_t> axis_evaluated_{0}, geometry_evaluated_{0}, geometry_full_{0}, parts_evaluated_{0};
  tbb::enumerable_thread_specific<Marks> marks_;
  tbb::enumerable_thread_specific<ExtentSlots> extent_slots_;
  tbb::enumerable_thread_specific<std::array<ExtentSlots, 2>> split_slots_;  ///< apply_split: both sides
  /// Per node: the extents its split gathered, until the node is evaluated.
  std::vector<std::unique_ptr<NodeExtents>> pending_ext_;
  tbb::enumerable_thread_specific<PointMarks> point_marks_;
  tbb::enumerable_thread_specific<std::pair<Marks, Marks>> side_pair_marks_;  ///< geometry-aligned: both sides
  tbb::enumerable_thread_specific<Marks> triangle_marks_;  ///< geometry-aligned: triangles hit in a cell
  tbb::enumerable_thread_specific<std::vector<uint32_t>> extreme_entry_;  ///< geometry-aligned: see extremes
  mutable tbb::enumerable_thread_specific<std::array<DrawnSet, 3>> drawn_;
};

}  // namespace

Subdivision subdivide(const Scene& scene, const SegmentSet& segments, const CostModel& model,
                      const SubdivisionConfig& config) {
  model.validate();
  if (config.max_cells < 1) throw Error("the maximum number of cells must be at least 1");
  if (config.split_round < 1) throw Error("a round of splits must take at least one cell");
  if (config.density.enabled &&
      !(config.density.lo < config.density.hi && config.density.outside >= 0 && std::isfinite(config.density.outside)))
    throw Error("viewpoint density band needs lo < hi and a finite, non-negative outside weight");
  if (config.viewpoints && config.density.enabled)
    throw Error("the viewpoint density is either a height band or points, not both");
  // The objects seen and the triangles hit (geometry-aligned candidates are their planes; a set
  // built by hand may carry no triangles), in one pass.
  auto refuse = [&](size_t i, const char* what, uint32_t id, size_t count) {
    throw Error("segment " + std::to_string(i) + " names " + what + " " + std::to_string(id) + ", but the scene has " +
                std::to_string(count) + " (segments of another scene?)");
  };
  for (size_t i = 0; i < segments.size(); ++i) {
    for (uint32_t o : {segments.object_a[i], segments.object_b[i]})
      if (o != kNoObject && o >= scene.objects.size()) refuse(i, "object", o, scene.objects.size());
    for (uint32_t t : {triangle_of(segments.triangle_a, i), triangle_of(segments.triangle_b, i)})
      if (t != kNoObject && t >= scene.triangles.size()) refuse(i, "triangle", t, scene.triangles.size());
  }
  Subdivision out;
  Builder(scene, segments, model, config, out).run();
  return out;
}

std::vector<std::vector<uint32_t>> leaf_pvs(const Subdivision& s, const SegmentSet& segments) {
  std::vector<std::vector<uint32_t>> pvs(s.nodes.size());
  const std::vector<int32_t> leaves = s.leaves();
  uint32_t objects = 0;  // one past the largest object id named
  // Each segment's two objects side by side: a leaf reads them by segment id, one place each.
  std::vector<std::array<uint32_t, 2>> ends(segments.size());
  for (size_t i = 0; i < segments.size(); ++i) {
    ends[i] = {segments.object_a[i], segments.object_b[i]};
    for (uint32_t o : ends[i])
      if (o != kNoObject) objects = std::max(objects, o + 1);
  }
  // Each leaf's distinct objects, sorted; each leaf alone, in parallel. A leaf with many
  // segments against the object count sets bits and reads them in order (a pass over one bit
  // per object); one with few marks the objects it meets first and sorts them.
  const size_t words = (objects + 63) / 64;
  tbb::enumerable_thread_specific<Marks> marks;
  tbb::enumerable_thread_specific<std::vector<uint64_t>> bits([words] { return std::vector<uint64_t>(words, 0); });
  tbb::parallel_for(size_t{0}, leaves.size(), [&](size_t l) {
    const std::vector<uint32_t>& in = s.segments[leaves[l]];
    auto& ids = pvs[leaves[l]];
    if (words <= 2 * in.size()) {
      std::vector<uint64_t>& b = bits.local();
      for (uint32_t i : in)
        for (uint32_t o : ends[i])
          if (o != kNoObject) b[o >> 6] |= uint64_t{1} << (o & 63);
      size_t count = 0;
      for (uint64_t x : b) count += static_cast<size_t>(__builtin_popcountll(x));
      ids.reserve(count);
      for (size_t w = 0; w < words; ++w)
        for (uint64_t x = std::exchange(b[w], 0); x; x &= x - 1)
          ids.push_back(static_cast<uint32_t>(w * 64 + static_cast<size_t>(__builtin_ctzll(x))));
      return;
    }
    Marks& m = marks.local();
    m.reset(objects);
    for (uint32_t i : in)
      for (uint32_t o : ends[i])
        if (m.first(o)) ids.push_back(o);
    std::sort(ids.begin(), ids.end());
  });
  return pvs;
}

void rebuild_cells(Subdivision& s) {
  s.cells.assign(s.nodes.size(), ConvexPolyhedron());
  s.cells[0] = ConvexPolyhedron::box(s.view_box, 0);
  for (const SplitRecord& r : s.splits) {
    const BspNode& n = s.nodes[r.node];
    auto halves = s.cells[r.node].split(s.planes[n.plane], n.plane);
    if (!halves) throw Error("replaying split of node " + std::to_string(r.node) + " failed (corrupt file?)");
    s.cells[n.child[0]] = std::move(halves->first);
    s.cells[n.child[1]] = std::move(halves->second);
    s.cells[r.node] = ConvexPolyhedron();
  }
}

}  // namespace viewcells
