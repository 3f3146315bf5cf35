// The subdivision's baselines (paper section 6): kd-tree splits at the middle of the longest
// or cycling axis, and polygon-BSP splits on the planes of the cell's polygons.
#include "bsp/subdivision_builder.h"

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

#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells::subdivision_detail {

Candidate Builder::kd_candidate(int32_t node) const {
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

Candidate Builder::best_polygon_candidate(int32_t node, Evaluation& ev) {
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

}  // namespace viewcells::subdivision_detail
