// Merging decided on AGVS's PVSs and started where held-out samples say it pays
// (eval/validated_merge.h).
#include "viewcells/eval/validated_merge.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <tbb/parallel_for.h>

#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"
#include "viewcells/eval/evaluate.h"

namespace viewcells {

namespace {

std::vector<std::vector<uint32_t>> unite(const std::vector<std::vector<uint32_t>>& a,
                                         const std::vector<std::vector<uint32_t>>& b) {
  std::vector<std::vector<uint32_t>> out(a.size());
  for (size_t n = 0; n < a.size(); ++n) out[n] = unite_sorted(a[n], b[n]);
  return out;
}

/// Every merge of `h`, in order, as a prefix that replays it.
std::vector<std::pair<int32_t, int32_t>> merges_of(const MergeHistory& h) {
  std::vector<std::pair<int32_t, int32_t>> out;
  for (size_t k = h.leaf_count; k < h.nodes.size(); ++k) out.emplace_back(h.nodes[k].child[0], h.nodes[k].child[1]);
  return out;
}

}  // namespace

LeafMerge merge_validated(const Scene& scene, const RayCaster& caster, const Subdivision& s,
                          std::vector<std::vector<uint32_t>> base, const CostModel& model,
                          const ValidatedMergeConfig& config) {
  LeafMerge out;
  MergeSummary& sum = out.summary;
  sum.validated = true;
  Stopwatch t;
  const LeafPvsRun a = leaf_pvs_by_agvs(scene, caster, s, config.agvs, base);
  base.clear();
  AgvsConfig vc = config.agvs;
  vc.seed += 1;
  const LeafPvsRun b = leaf_pvs_by_agvs(scene, caster, s, vc);
  sum.merge_agvs_samples = a.stats.samples;
  sum.validation_agvs_samples = b.stats.samples;
  sum.leaf_pvs_seconds = t.seconds();

  t.restart();
  CellPartition partition = partition_from_subdivision(s, a.pvs);
  sum.neighbour_seconds = t.seconds();

  t.restart();
  const size_t L = s.leaf_count();
  MergeConfig mc = config.merge;
  mc.prefix = subdivision_prefix(s, 1);
  const MergeHistory av_s = merge_cells(scene, partition, model, mc);  // AV-S's own order
  const CostCurve av_s_held_out = evaluate_merge_history(scene, s, av_s, b.pvs, model);
  std::vector<size_t> counts;
  for (size_t n = std::min<size_t>(config.score_from, L); n <= L; n = n * 5 / 4 + 1) counts.push_back(n);
  if (counts.empty() || counts.back() != L) counts.push_back(L);
  sum.chosen = {1, 0, 0.0, 0.0};
  sum.starts.push_back(sum.chosen);
  mc.show_progress = false;
  // Every candidate start, scored in parallel (each is independent; the choice below is made
  // in a fixed order, so it does not depend on the thread count).
  std::vector<MergeStart> candidates;
  for (size_t start = L; start >= 2; start /= 2) {
    candidates.push_back({static_cast<uint32_t>(start), 0, 0.0, 0.0});
    for (size_t barrier = start / 4; barrier >= 4; barrier /= 4)
      candidates.push_back({static_cast<uint32_t>(start), static_cast<uint32_t>(barrier), 0.0, 0.0});
  }
  auto config_for = [&](const MergeStart& st) {
    MergeConfig c = mc;
    c.prefix = subdivision_prefix(s, st.cells);
    c.barrier_cells = st.barrier;
    c.block = st.barrier ? subdivision_blocks(s, st.barrier) : std::vector<int32_t>{};
    return c;
  };
  Progress progress("choosing where merging starts", candidates.size());
  std::atomic<uint64_t> evaluations{0}, stale{0};  // the candidates' pair costs, for the report
  tbb::parallel_for(size_t{0}, candidates.size(), [&](size_t i) {
    MergeStart& st = candidates[i];
    const MergeHistory h = merge_cells(scene, partition, model, config_for(st));
    evaluations += h.stats.evaluations;
    stale += h.stats.stale;
    const CostCurve held_out = evaluate_merge_history(scene, s, h, b.pvs, model);
    st.worst = -1e300;
    size_t terms = 0;
    for (size_t n : counts)
      if (n >= h.min_cells() && n >= av_s.min_cells()) {
        const double r = std::log(held_out.at(static_cast<uint32_t>(n)) / av_s_held_out.at(static_cast<uint32_t>(n)));
        st.score += r;
        st.worst = std::max(st.worst, r);
        ++terms;
      }
    st.score = terms ? st.score / static_cast<double>(terms) : 0.0;
    if (!terms) st.worst = 0;
    if (config.merge.show_progress) progress.advance(1);
  });
  if (config.merge.show_progress) progress.finish();
  // The lowest mean among the starts whose worst count stays within the allowance; ties keep
  // the earlier (AV-S's order first).
  for (const MergeStart& st : candidates) {
    sum.starts.push_back(st);
    if (st.worst <= config.worst_allowed && st.score < sum.chosen.score) sum.chosen = st;
  }
  const MergeHistory best = sum.chosen.cells == 1 ? av_s : merge_cells(scene, partition, model, config_for(sum.chosen));
  sum.merge_seconds = t.seconds();

  // The chosen merges, replayed with every sample's PVSs.
  t.restart();
  out.leaf_pvs = unite(a.pvs, b.pvs);
  partition = partition_from_subdivision(s, out.leaf_pvs);
  sum.neighbour_seconds += t.seconds();
  t.restart();
  mc.prefix = merges_of(best);
  mc.barrier_cells = 0;
  mc.block.clear();
  mc.show_progress = config.merge.show_progress;
  out.history = merge_cells(scene, partition, model, mc);
  sum.merge_seconds += t.seconds();
  out.history.stats.seconds = sum.merge_seconds;
  out.history.stats.evaluations = evaluations.load();  // the replay itself chooses nothing
  out.history.stats.stale = stale.load();
  return out;
}

LeafMerge merge_leaves(const Scene& scene, const RayCaster& caster, const Subdivision& s, const SegmentSet& segments,
                       const CostModel& model, const std::optional<AgvsConfig>& agvs, const MergeConfig& merge) {
  Stopwatch t;
  std::vector<std::vector<uint32_t>> base = leaf_pvs(s, segments);
  const double base_seconds = t.seconds();
  LeafMerge out;
  if (agvs) {
    ValidatedMergeConfig vc;
    vc.agvs = *agvs;
    vc.merge = merge;
    out = merge_validated(scene, caster, s, std::move(base), model, vc);
  } else {
    MergeSummary& sum = out.summary;
    sum.chosen = {static_cast<uint32_t>(s.leaf_count()), 0, 0.0, 0.0};
    t.restart();
    CellPartition partition = partition_from_subdivision(s, std::move(base));
    sum.neighbour_seconds = t.seconds();
    t.restart();
    out.history = merge_cells(scene, partition, model, merge);
    sum.merge_seconds = t.seconds();
    // The leaves' lists back, per node.
    const std::vector<int32_t> leaves = s.leaves();
    out.leaf_pvs.assign(s.nodes.size(), {});
    for (size_t i = 0; i < leaves.size(); ++i) out.leaf_pvs[leaves[i]] = std::move(partition.pvs[i]);
  }
  out.summary.leaf_pvs_seconds += base_seconds;
  return out;
}

}  // namespace viewcells
