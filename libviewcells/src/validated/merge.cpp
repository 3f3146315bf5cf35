// Merging decided on AGVS's PVSs and started where held-out samples say it pays
// (validated/merge.h).
#include "viewcells/validated/merge.h"

#include "validated/merge_choice.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>

#include <tbb/parallel_for.h>

#include "viewcells/scene/cost_model.h"
#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"
#include "viewcells/eval/evaluate.h"

namespace viewcells {

namespace {

using Merges = std::vector<std::pair<int32_t, int32_t>>;

/// Per leaf, the least leaf of its cell after the first `k` of `merges` (merges_by_least_leaf).
std::vector<int32_t> cut_labels(const Merges& merges, size_t leaves, size_t k) {
  std::vector<int32_t> up(leaves);
  for (size_t n = 0; n < leaves; ++n) up[n] = static_cast<int32_t>(n);
  for (size_t j = 0; j < k && j < merges.size(); ++j) {
    const auto [a, b] = merges[j];
    up[std::max(a, b)] = std::min(a, b);  // both name current cells: roots
  }
  for (size_t n = 0; n < leaves; ++n) up[n] = up[up[n]];  // parents have smaller ids: done in order
  return up;
}

/// A count's worst held-out log ratio raised by `margin` times its distance from the sets' mean
/// (ValidatedMergeConfig::spread_margin).
double raised_worst(double worst, double mean, double margin) { return worst + margin * (worst - mean); }

/// The held-out leaf PVS sets (B, and C when drawn), AV-S's costs on each, and the counts scored.
struct HeldOut {
  std::vector<const std::vector<std::vector<uint32_t>>*> pvs;
  std::vector<CostCurve> av_s;
  std::vector<MergeReplayCuts> replays;  ///< per set: AV-S's replay, kept at the candidates' starts
  std::vector<size_t> counts;
  size_t av_s_min_cells = 1;

  CandidateScores score(const Scene& scene, const Subdivision& s, const MergeHistory& h, const CostModel& model) const {
    CandidateScores out{std::vector<double>(counts.size(), 0.0), std::vector<double>(counts.size(), 0.0),
                        std::vector<uint8_t>(counts.size(), 0)};
    for (size_t k = 0; k < pvs.size(); ++k) {
      // Every candidate begins with AV-S's own merges down to its start: replayed from there.
      const CostCurve curve = merge_history_curve(h, evaluated_merge_costs(scene, s, h, *pvs[k], model, replays[k]));
      for (size_t j = 0; j < counts.size(); ++j) {
        const auto n = static_cast<uint32_t>(counts[j]);
        if (n < h.min_cells() || n < av_s_min_cells) continue;
        const double r = std::log(curve.at(n) / av_s[k].at(n));
        out.log_ratio[j] += r / static_cast<double>(pvs.size());
        out.worst[j] = k ? std::max(out.worst[j], r) : r;
        out.scored[j] = 1;
      }
    }
    return out;
  }
  /// The mean over the counts scored, and the worst count (raw and with `margin`), as
  /// MergeStart reports them.
  void summarise(const CandidateScores& c, size_t min_cells, double margin, MergeStart& st) const {
    st.score = 0;
    st.worst = 0;
    st.worst_with_margin = 0;
    size_t terms = 0;
    for (size_t j = 0; j < counts.size(); ++j)
      if (counts[j] >= min_cells && counts[j] >= av_s_min_cells) {
        st.score += c.log_ratio[j];
        const double raised = raised_worst(c.worst[j], c.log_ratio[j], margin);
        st.worst = terms ? std::max(st.worst, c.worst[j]) : c.worst[j];
        st.worst_with_margin = terms ? std::max(st.worst_with_margin, raised) : raised;
        ++terms;
      }
    if (terms) st.score /= static_cast<double>(terms);
  }
};

/// A candidate's scores and merges.
struct Scored {
  CandidateScores at;
  Merges merges;  ///< by least leaf
};

/// The lowest sum of log ratios for the counts at most `c`, from AV-S's cut at `c` down.
struct Tail {
  double sum = 0;
  int candidate = -1;  ///< -1: AV-S's own order
  bool split = false;  ///< the candidate down to its barrier, then tails[barrier]
};

}  // namespace

bool merge_piece_allowed(double sum, double worst, size_t counts, double worst_allowed) {
  return worst <= worst_allowed && (counts == 0 || worst <= -sum / static_cast<double>(counts));
}

bool merge_piece_within(const PieceAllowance& allowed, bool refined, double sum, double worst, double worst_low,
                        size_t counts) {
  if (!refined) return merge_piece_allowed(sum, std::max(worst, worst_low), counts, allowed.greedy);
  return worst_low <= allowed.refined_low && merge_piece_allowed(sum, worst, counts, allowed.refined);
}

std::vector<ChosenPiece> choose_merge_pieces(const std::vector<MergeStart>& candidates,
                                             const std::vector<CandidateScores>& scores,
                                             const std::vector<size_t>& counts, uint32_t leaves,
                                             const PieceAllowance& allowed, double spread_margin) {
  VC_CHECK(scores.size() == candidates.size());
  for (const CandidateScores& sc : scores)
    VC_CHECK(sc.log_ratio.size() == counts.size() && sc.worst.size() == counts.size() && sc.scored.size() == counts.size());
  // tails[c]: the best history below AV-S's cut at c cells, scored on the counts at most c; c
  // runs over the barriers, upwards, and the leaves.
  std::vector<uint32_t> ends{leaves};
  for (const MergeStart& st : candidates)
    if (st.barrier) ends.push_back(st.barrier);
  std::sort(ends.begin(), ends.end());
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  std::vector<Tail> tails(ends.size());
  auto tail_at = [&](uint32_t c) -> const Tail& {
    return tails[static_cast<size_t>(std::lower_bound(ends.begin(), ends.end(), c) - ends.begin())];
  };
  struct Piece {
    double sum = 0, worst = 0, worst_low = 0;  // worst_low: below allowed.low_below
    size_t counts = 0;
  };
  // Sum and worst on counts in (below, upto]; a count's worst raised by the margin on the sets'
  // disagreement.
  auto piece = [&](size_t i, uint32_t below, uint32_t upto) {
    Piece p;
    for (size_t j = 0; j < counts.size(); ++j)
      if (counts[j] > below && counts[j] <= upto) {
        p.sum += scores[i].log_ratio[j];
        double& w = counts[j] < allowed.low_below ? p.worst_low : p.worst;
        w = std::max(w, raised_worst(scores[i].worst[j], scores[i].log_ratio[j], spread_margin));
        p.counts += scores[i].scored[j];
      }
    return p;
  };
  constexpr double kGain = 1e-9;  // rounding, in a sum of log ratios
  auto within = [&](size_t i, const Piece& p) {
    return merge_piece_within(allowed, candidates[i].refined, p.sum, p.worst, p.worst_low, p.counts);
  };
  for (size_t e = 0; e < ends.size(); ++e) {
    const uint32_t c = ends[e];
    Tail best;  // AV-S's own order: 0
    for (size_t i = 0; i < candidates.size(); ++i) {
      const MergeStart& st = candidates[i];
      if (st.cells > c) continue;
      // This candidate's option: whole, or down to its barrier and the best tail there when
      // that does at least as well.
      const Piece whole = piece(i, 0, c);
      std::optional<Tail> option;
      if (within(i, whole)) option = Tail{whole.sum, static_cast<int>(i), false};
      if (st.barrier && scores[i].barrier_cut) {
        const Piece upper = piece(i, st.barrier, c);
        const Tail& below = tail_at(st.barrier);
        const double split = upper.sum + below.sum;
        if (within(i, upper) && (!option || split <= option->sum + kGain))
          option = Tail{split, static_cast<int>(i), true};
      }
      if (option && option->sum < best.sum - kGain) best = *option;
    }
    tails[e] = best;
  }
  std::vector<ChosenPiece> out;  // from the leaves down
  for (uint32_t c = leaves;;) {
    const Tail& tail = tail_at(c);
    const uint32_t to = tail.split ? candidates[static_cast<size_t>(tail.candidate)].barrier : 0;
    out.push_back({tail.candidate, c, to});
    if (!tail.split) break;
    c = to;
  }
  return out;
}

namespace {

/// The held-out random samples' leaf PVSs (their count into `drawn`): drawn and walked a
/// million samples at a time (every leaf each segment has length in), so that the segments are
/// never all held: the same lists as walking them at once.
std::vector<std::vector<uint32_t>> held_out_leaf_pvs(const Scene& scene, const RayCaster& caster,
                                                     const Subdivision& s, const ValidatedMergeConfig& config,
                                                     uint64_t& drawn) {
  SamplerConfig sc = *config.held_out_samples;
  sc.show_progress = sc.show_progress && config.merge.show_progress;
  EvaluationPvs gathered(s, scene.objects.size());
  drawn = sample_in_chunks(scene, caster, sc, kHeldOutChunk, [&](const SegmentSet& chunk, uint64_t) {
            gathered.add(chunk);
          }).samples;
  return gathered.take();
}

/// Where greedy merging may start: AV-S's cut at every halving of the L leaves, alone or held
/// within its cuts at every quartering below; and, without a pixel term, refined at low counts:
/// from AV-S's cut at `cells`, its cells are moved between the blocks of AV-S's cut at
/// `barrier` (64 or 32 cells) where the merge PVSs say it lowers the cost; merging joins within
/// those blocks down to `barrier`, and at every halving below, the cells of the count above are
/// moved between the blocks greedy merging reaches, and merging goes on within them. The units
/// moved are AV-S's cells at 4 to 64 per block: finer ones fit the merge PVSs' noise (on the
/// office, refined histories from 2,500 and 5,000 cells scored 1-9% worse than AV-S on the
/// held-out samples, from 312 cells 2-5% better). Blocks of 32 cells: the office's and the
/// town's choice at low counts (docs/accuracy-vs-time.md, section 5).
std::vector<MergeStart> candidate_starts(size_t L, const CostModel& model) {
  std::vector<MergeStart> candidates;
  for (size_t start = L; start >= 2; start /= 2) {
    candidates.push_back({static_cast<uint32_t>(start), 0, 0.0, 0.0});
    for (size_t barrier = start / 4; barrier >= 4; barrier /= 4)
      candidates.push_back({static_cast<uint32_t>(start), static_cast<uint32_t>(barrier), 0.0, 0.0});
  }
  if (!model.pixel_term())
    for (const uint32_t barrier : {64u, 32u})
      for (size_t start = L; start >= 4 * barrier; start /= 2)
        if (start <= 64 * barrier) candidates.push_back({static_cast<uint32_t>(start), barrier, 0.0, 0.0, true});
  return candidates;
}

/// A refined candidate's history `h`, from its first merging on: at every halving below its
/// barrier, the cells of the count above moved between the blocks merging reached, and merging
/// gone on within them (`mc`: the merge's config; L leaves).
MergeHistory refined_below_barrier(const Scene& scene, const CellPartition& partition, const CostModel& model,
                                   const MergeConfig& mc, size_t L, const MergeStart& st, MergeHistory h) {
  for (size_t up = st.barrier, k = up / 2; k >= 4 && h.min_cells() <= k; up = k, k /= 2) {
    const Merges m = merges_by_least_leaf(h);
    const std::vector<int32_t> blocks = cut_labels(m, L, L - k);
    const std::vector<int32_t> refined = refine_blocks(scene, partition, model, cut_labels(m, L, L - up), blocks);
    if (refined == blocks) continue;
    MergeConfig c = mc;
    c.prefix = least_leaf_merges_as_prefix(Merges(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(L - up)), L);
    c.barrier_cells = static_cast<uint32_t>(k);
    c.block = refined;
    const MergeStats before = h.stats;
    h = merge_cells(scene, partition, model, c);
    h.stats.evaluations += before.evaluations;
    h.stats.stale += before.stale;
  }
  return h;
}

/// The chosen history's merges, piece by piece, named by least leaf; each piece recorded in
/// `sum.chain`.
Merges chosen_merges(const std::vector<ChosenPiece>& pieces, const std::vector<MergeStart>& candidates,
                     const std::vector<Scored>& scored, const Merges& av_s_merges, size_t L, MergeSummary& sum) {
  Merges chosen;
  for (const ChosenPiece& p : pieces) {
    const Merges& m = p.candidate < 0 ? av_s_merges : scored[static_cast<size_t>(p.candidate)].merges;
    const MergeStart st =
        p.candidate < 0 ? MergeStart{1, 0, 0.0, 0.0} : candidates[static_cast<size_t>(p.candidate)];
    const size_t first = L - p.from, last = p.to ? L - p.to : m.size();
    chosen.insert(chosen.end(), m.begin() + static_cast<std::ptrdiff_t>(std::min(first, m.size())),
                  m.begin() + static_cast<std::ptrdiff_t>(std::min(last, m.size())));
    sum.chain.push_back({st, p.from, p.to});
  }
  return chosen;
}

/// The chosen merges, replayed with every sample's PVSs (`out.history`): the same partition
/// (cells and neighbours), each leaf's list united in place with both held-out sets' (`b_pvs`,
/// and `c_pvs` when drawn), then moved out into `out.leaf_pvs`, per node.
void replay_chosen(const Scene& scene, const Subdivision& s, const CostModel& model, const ValidatedMergeConfig& config,
                   const Merges& chosen, const std::vector<std::vector<uint32_t>>& b_pvs,
                   const std::vector<std::vector<uint32_t>>& c_pvs, MergeConfig mc, CellPartition& partition,
                   LeafMerge& out) {
  MergeSummary& sum = out.summary;
  Stopwatch t;
  const std::vector<int32_t> leaves = s.leaves();
  tbb::parallel_for(size_t{0}, leaves.size(), [&](size_t i) {
    std::vector<uint32_t>& l = partition.pvs[i];
    l = unite_sorted(l, b_pvs[leaves[i]]);
    if (config.held_out_samples) l = unite_sorted(l, c_pvs[leaves[i]]);
  });
  sum.neighbour_seconds += t.seconds();
  t.restart();
  mc.prefix = least_leaf_merges_as_prefix(chosen, s.leaf_count());
  mc.barrier_cells = 0;
  mc.block.clear();
  mc.show_progress = config.merge.show_progress;
  out.history = merge_cells(scene, partition, model, mc);
  sum.merge_seconds += t.seconds();
  out.leaf_pvs.assign(s.nodes.size(), {});
  for (size_t i = 0; i < leaves.size(); ++i) out.leaf_pvs[leaves[i]] = std::move(partition.pvs[i]);
}

}  // namespace

LeafMerge merge_validated(const Scene& scene, const RayCaster& caster, const Subdivision& s,
                          std::vector<std::vector<uint32_t>> base, const CostModel& model,
                          const ValidatedMergeConfig& config) {
  LeafMerge out;
  MergeSummary& sum = out.summary;
  sum.validated = true;
  Stopwatch t;
  LeafPvsRun a = leaf_pvs_by_agvs(scene, caster, s, config.agvs, base);
  base.clear();
  AgvsConfig vc = config.agvs;
  vc.seed += 1;
  const LeafPvsRun b = leaf_pvs_by_agvs(scene, caster, s, vc);
  sum.merge_agvs_samples = a.stats.samples;
  sum.validation_agvs_samples = b.stats.samples;
  std::vector<std::vector<uint32_t>> c_pvs;
  if (config.held_out_samples) c_pvs = held_out_leaf_pvs(scene, caster, s, config, sum.held_out_samples);
  sum.leaf_pvs_seconds = t.seconds();

  t.restart();
  CellPartition partition = partition_from_subdivision(s, std::move(a.pvs));
  sum.neighbour_seconds = t.seconds();

  t.restart();
  const size_t L = s.leaf_count();
  MergeConfig mc = config.merge;
  mc.prefix = subdivision_prefix(s, 1);
  const MergeHistory av_s = merge_cells(scene, partition, model, mc);  // AV-S's own order
  HeldOut held_out;
  held_out.pvs.push_back(&b.pvs);
  if (config.held_out_samples) held_out.pvs.push_back(&c_pvs);
  held_out.av_s_min_cells = av_s.min_cells();
  std::vector<size_t>& counts = held_out.counts;
  for (size_t n = std::min<size_t>(config.score_from, L); n <= L; n = n * 5 / 4 + 1) counts.push_back(n);
  if (counts.empty() || counts.back() != L) counts.push_back(L);
  sum.chosen = {1, 0, 0.0, 0.0};
  sum.starts.push_back(sum.chosen);
  mc.show_progress = false;
  // Every candidate start, scored in parallel (each is independent; the choice below is made
  // in a fixed order, so it does not depend on the thread count).
  std::vector<MergeStart> candidates = candidate_starts(L, model);
  // AV-S's replay on each held-out set, kept at every candidate's start (its first L - start
  // merges are AV-S's own), and AV-S's curves.
  std::vector<size_t> starts;
  for (const MergeStart& st : candidates) starts.push_back(L - st.cells);
  for (const auto* pvs : held_out.pvs) {
    held_out.replays.push_back(replay_merge_cuts(scene, s, av_s, *pvs, model, starts));
    const MergeReplayCuts& replay = held_out.replays.back();
    held_out.av_s.push_back(replay.r.empty() ? evaluate_merge_history(scene, s, av_s, *pvs, model)
                                             : merge_history_curve(av_s, replay.r));
  }
  auto config_for = [&](const MergeStart& st) {
    MergeConfig c = mc;
    c.prefix = subdivision_prefix(s, st.cells);
    c.barrier_cells = st.barrier;
    c.block = st.barrier ? subdivision_blocks(s, st.barrier) : std::vector<int32_t>{};
    if (st.refined) c.block = refine_blocks(scene, partition, model, subdivision_blocks(s, st.cells), c.block);
    return c;
  };
  // A refined candidate's history, from its first merging (config_for) on: at every halving
  // below its barrier, the cells of the count above moved between the blocks merging reached.
  auto refined_on = [&](const MergeStart& st, MergeHistory h) {
    return refined_below_barrier(scene, partition, model, mc, L, st, std::move(h));
  };
  Progress progress("choosing where merging starts", candidates.size());
  std::atomic<uint64_t> evaluations{0}, stale{0};  // the candidates' pair costs, for the report
  const Merges av_s_merges = merges_by_least_leaf(av_s);
  std::vector<Scored> scored(candidates.size());
  // Every candidate begins with AV-S's own merges down to its start: they are merged once, and
  // each candidate merges on from a copy of that state (the same history as merging alone).
  std::vector<MergeConfig> configs(candidates.size());
  tbb::parallel_for(size_t{0}, candidates.size(), [&](size_t i) { configs[i] = config_for(candidates[i]); });
  merge_cells_sharing_prefix(scene, partition, model, configs, [&](size_t i, MergeHistory first) {
    MergeStart& st = candidates[i];
    const MergeHistory h = st.refined ? refined_on(st, std::move(first)) : std::move(first);
    evaluations += h.stats.evaluations;
    stale += h.stats.stale;
    Scored& sc = scored[i];
    sc.at = held_out.score(scene, s, h, model);
    held_out.summarise(sc.at, h.min_cells(), config.spread_margin, st);
    sc.merges = merges_by_least_leaf(h);
    sc.at.barrier_cut = st.barrier && h.min_cells() <= st.barrier &&
                     cut_labels(sc.merges, L, L - st.barrier) == cut_labels(av_s_merges, L, L - st.barrier);
    if (config.merge.show_progress) progress.advance(1);
  });
  if (config.merge.show_progress) progress.finish();
  configs.clear();
  configs.shrink_to_fit();
  sum.starts.insert(sum.starts.end(), candidates.begin(), candidates.end());

  std::vector<CandidateScores> scores;
  for (Scored& sc : scored) scores.push_back(std::move(sc.at));
  const std::vector<ChosenPiece> pieces =
      choose_merge_pieces(candidates, scores, counts, static_cast<uint32_t>(L), config.allowed, config.spread_margin);

  const Merges chosen = chosen_merges(pieces, candidates, scored, av_s_merges, L, sum);
  sum.chosen = sum.chain.front().start;
  sum.merge_seconds = t.seconds();

  replay_chosen(scene, s, model, config, chosen, b.pvs, c_pvs, mc, partition, out);
  // The whole chosen history's held-out score, as the candidates were scored.
  held_out.summarise(held_out.score(scene, s, out.history, model), out.history.min_cells(), config.spread_margin,
                     sum.chosen);
  out.history.stats.seconds = sum.merge_seconds;
  out.history.stats.evaluations = evaluations.load();  // the replay itself chooses nothing
  out.history.stats.stale = stale.load();
  return out;
}

SamplerConfig held_out_sampling(const SamplerConfig& construction, uint64_t samples_drawn) {
  SamplerConfig c = construction;
  c.seed = construction.seed + 2000003;
  c.target_segments = 0;
  c.samples = std::max<uint64_t>(kHeldOutPerConstructionSample * samples_drawn, 1);
  return c;
}

std::string describe_chain(const MergeSummary& summary) {
  std::string out;
  for (const MergePiece& p : summary.chain) {
    if (!out.empty()) out += "; from " + std::to_string(p.from) + " cells: ";
    if (p.start.cells <= 1) {
      out += "the subdivision's own order";
      continue;
    }
    out += "greedy merging from the subdivision's own cut at " + std::to_string(p.start.cells) + " cells";
    if (p.start.barrier && p.start.refined)
      out += ", within its cut at " + std::to_string(p.start.barrier) +
             " cells refined by moving cells between neighbouring blocks until there" +
             (p.to ? std::string() : ", and so at every halving below");
    else if (p.start.barrier)
      out += ", within its cut at " + std::to_string(p.start.barrier) + " cells until there";
  }
  return out;
}

LeafMerge merge_leaves(const Scene& scene, const RayCaster& caster, const Subdivision& s, const SegmentSet& segments,
                       const SamplerConfig& held_out, const CostModel& model,
                       const std::optional<AgvsConfig>& agvs, const MergeConfig& merge) {
  Stopwatch t;
  std::vector<std::vector<uint32_t>> base = leaf_pvs(s, segments);
  const double base_seconds = t.seconds();
  LeafMerge out;
  if (agvs) {
    ValidatedMergeConfig vc;
    vc.agvs = *agvs;
    vc.merge = merge;
    vc.held_out_samples = held_out;
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
