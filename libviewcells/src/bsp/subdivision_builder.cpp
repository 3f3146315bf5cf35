// The subdivision's queue driver (paper section 4.2): cells taken from a priority queue by
// their best split's cost reduction, in parallel rounds whose results equal one split at a time.
#include "bsp/subdivision_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <chrono>
#include <optional>
#include <queue>
#include <utility>
#include <vector>

#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells::subdivision_detail {

void Builder::start_tree() {
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
  best_.resize(1);
  if (gathers_extents()) pending_ext_.push_back(std::make_unique<NodeExtents>(node_extents(refs_[0])));
  const Evaluation first = evaluate(0);
  best_[0] = first.best;
  count_evaluation(0, first);
  if (best_[0].valid) queue_.push({priority(0), 0});
}

void Builder::take_round(std::vector<PendingSplit>& round, size_t round_size) {
  // The first cells of the queue, with their cells cut, up to the splits still wanted; the
  // planes of those that cut are added (the children's new faces name them) in this order.
  round.clear();
  size_t cuts = 0;
  while (!queue_.empty() && round.size() < round_size && cuts < config_.max_cells - out_.leaf_count()) {
    PendingSplit& p = round.emplace_back();
    p.node = queue_.top().second;
    queue_.pop();
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
}

size_t Builder::replay_round(const std::vector<PendingSplit>& round, size_t first_child,
                             const std::vector<Evaluation>& evaluations, Progress& progress) {
  size_t done = 0, next_child = first_child;
  for (; done < round.size(); ++done) {
    const PendingSplit& p = round[done];
    if (!queue_.empty() && QueueOrder{}({priority(p.node), p.node}, queue_.top())) break;  // a child comes first
    stagnant_ = p.cand.reduction < config_.min_reduction * out_.initial_cost ? stagnant_ + 1 : 0;
    if (config_.strategy == SplitStrategy::kCost && stagnant_ >= config_.stagnation_steps) {
      out_.stats.stop_reason = "the cost reduction stayed below the threshold for " +
                               std::to_string(config_.stagnation_steps) + " successive splits";
      stopped_ = true;
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
    cost_ += after - before;
    out_.splits.push_back({p.node, before - after, cost_});
    for (int32_t c : {c0, c1})
      if (best_[c].valid) queue_.push({priority(c), c});
    if (config_.show_progress) progress.advance(1);
  }
  // The rest of the round: its children removed, its cells back in the queue (unless stopped).
  if (done < round.size()) {
    truncate_nodes(next_child);
    if (!stopped_) {
      for (size_t i = done; i < round.size(); ++i) queue_.push({priority(round[i].node), round[i].node});
      splits_undone_ += round.size() - done;
    }
  }
  return done;
}

void Builder::finish_tree() {
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
}

void Builder::run() {
  const auto start = std::chrono::steady_clock::now();
  start_tree();
  cost_ = out_.initial_cost;
  Progress progress("subdividing", config_.max_cells);
  if (config_.show_progress) progress.advance(1);
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
  while (!stopped_ && out_.leaf_count() < config_.max_cells) {
    throw_if_interrupted("subdivision");
    if (queue_.empty()) {
      out_.stats.stop_reason = config_.strategy == SplitStrategy::kCost
                                   ? "no cell can be split further (no candidate reduces the cost)"
                                   : "no cell is left to split under the method's own termination rule";
      break;
    }
    take_round(round, round_size);
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
    replay_round(round, first_child, evaluations, progress);  // the serial order
  }
  if (config_.show_progress) progress.finish();
  finish_tree();
  out_.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace viewcells::subdivision_detail
