// The subdivision's nodes (paper section 4.2): r(PVS) of a cell, the object costs its candidates
// are evaluated with, partitions of its segment parts by a plane, prepared and committed splits,
// and the evaluation that picks a cell's best candidate.
#include "bsp/subdivision_builder.h"
#include "bsp/segment_walk.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/global_control.h>

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

double Builder::pvs_cost(const ConvexPolyhedron& cell, const RawVector<SegRef>& refs) {
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

const double* Builder::candidate_costs(int32_t node, RawVector<double>& storage) {
  if (!model_.pixel_term()) return r_.data();
  storage.resize(r_.size());
  for_each_cell_cost(out_.cells[node], refs_[node], [&](uint32_t o, double r) { storage[o] = r; });
  return storage.data();
}

BspNode Builder::measure_node(int32_t parent, const ConvexPolyhedron& cell, const RawVector<SegRef>& refs,
                              const NodeExtents* ext) {
  BspNode node;
  node.parent = parent;
  node.volume = cell.volume();
  node.weight = config_.density.weight(cell);
  node.pvs_cost = ext && !model_.pixel_term() ? ext->pvs_cost(r_) : pvs_cost(cell, refs);
  return node;
}

Builder::Partition Builder::partition(int32_t node, const Plane& plane) {
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

void Builder::prepare_split(PendingSplit& p) {
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

void Builder::add_children(PendingSplit& p) {
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

void Builder::commit_split(const PendingSplit& p, int32_t c0) {
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

void Builder::truncate_nodes(size_t n) {
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

void Builder::count_evaluation(int32_t node, const Evaluation& e) {
  axis_evaluated_ += e.axis;
  parts_evaluated_ += refs_[node].size();
  geometry_evaluated_ += e.geometry;
  geometry_full_ += e.geometry_full;
}

Evaluation Builder::evaluate(int32_t node) {
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

}  // namespace viewcells::subdivision_detail
