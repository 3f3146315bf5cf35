// Axis-aligned candidate planes (paper section 4.2.1): positions drawn from the segment ends
// in a cell, and one sweep over the objects' extents that gives both sides' r(PVS) at every
// position.
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

std::array<std::vector<double>, 3> Builder::axis_positions(int32_t node, const Box3& bounds) const {
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

std::vector<double> Builder::all_axis_positions(int32_t node, int axis, const Box3& bounds) const {
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

void Builder::side_costs(const NodeExtents& ext, int axis, const std::vector<double>& x, const double* r,
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

NodeExtents Builder::join_extents(std::vector<NodeExtents>& chunks) {
  if (chunks.size() == 1) return std::move(chunks[0]);
  NodeExtents all;
  ExtentSlots& slots = extent_slots_.local();
  slots.reset(r_.size());
  for (const NodeExtents& c : chunks) slots.merge(c, all);
  slots.finish(all);
  return all;
}

NodeExtents Builder::node_extents(const RawVector<SegRef>& refs) {
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

Candidate Builder::best_axis_candidate(int32_t node, int axis, const std::vector<double>& positions, const NodeExtents& ext,
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

}  // namespace viewcells::subdivision_detail
