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
#include "bsp/subdivision_builder.h"
#include "viewcells/core/default_init.h"
#include "viewcells/core/error.h"
#include "viewcells/core/names.h"
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

namespace {
constexpr EnumNames<SplitStrategy, 6> kStrategyNames{{{{SplitStrategy::kCost, "av-s"},
                                                       {SplitStrategy::kKdCycling, "kd-casm"},
                                                       {SplitStrategy::kKdLongest, "kd-lasm"},
                                                       {SplitStrategy::kKdVisibility, "kd-vt"},
                                                       {SplitStrategy::kKdVisibilityDepthFirst, "kd-vt-star"},
                                                       {SplitStrategy::kPolygonBsp, "bsp"}}},
                                                     "subdivision method"};
}  // namespace

SplitStrategy parse_split_strategy(const std::string& name) { return kStrategyNames.parse(name); }

const char* to_string(SplitStrategy s) { return kStrategyNames.name(s); }

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

using subdivision_detail::Builder;
using subdivision_detail::Marks;
using subdivision_detail::triangle_of;

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
