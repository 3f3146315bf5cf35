#pragma once
/// Merging that holds under independent samples (view-cell-construction paper 4.3, made
/// robust to sampling noise). Greedy merging of elementary cells whose PVSs come from a few
/// hundred samples each picks the pairs whose sampled PVSs happen to overlap most: it fits the
/// gaps of the samples, and independent samples show cuts worse than the subdivision's own.
/// Two remedies, measured in docs/results.md:
///  1. the elementary cells' PVSs that merging decides on are the construction samples'
///     united with those of an AGVS run over the cells ("merge" run, A);
///  2. the greedy merging starts from a cut of the subdivision's own order (AV-S's, undone
///     split by split from the leaves), chosen on samples that no decision has seen: a
///     second, independent AGVS run (B) and four times as many random samples as the
///     construction drew, drawn the same way (C, the evaluator's kind of PVS). Each candidate,
///     greedy from every cut by halves, with and without barriers, or within blocks refined at
///     low counts, is scored by its log cost ratio to AV-S's cuts at log-spaced counts, on B
///     and on C separately. Pure AV-S (ratio 0) is a candidate, so merging is kept only where
///     the held-out samples say it pays. Where a candidate's cut is AV-S's own (at its
///     barrier), the histories below are interchangeable, so the choice is made per range of
///     counts: the lowest sum of the mean log ratios over all counts (a dynamic program over
///     the barriers), each piece within the allowance at every count on both B and C (with a
///     margin where B and C disagree; PieceAllowance: none for greedy pieces, a little for
///     refined ones, which cannot give way to AV-S's order below their barrier), and losing
///     at its worst count no more than it gains on average (else it is a tie, and ties keep
///     AV-S's order).
/// The history written has the chosen merges with PVSs from the construction samples, A, B
/// and C together (what extraction and compression then store).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/agvs/agvs.h"
#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/merge/merge.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// How far above AV-S's cut of the same size the held-out samples may rate the counts of a
/// piece merge_validated takes (log cost ratios; each count's worst held-out set, raised by the
/// sets' disagreement). Every piece must also lose at its worst count no more than it gains on
/// average (merge_piece_allowed).
struct PieceAllowance {
  /// Greedy pieces, at every count: rounding, so no count of such a piece may be rated worse
  /// than AV-S's cut by either held-out set. (Until 2026-12-03 it was 0.01: pieces that gained
  /// on average could lose up to 1% at some counts, and on 6 of 72 OpenArena maps independent
  /// samples then rated AV-M 0.1-0.8% worse than AV-S at q3map2's cluster count or a quarter.)
  double greedy = 1e-9;
  /// Refined pieces (MergeStart::refined), at counts from `low_below` up. A refined history's
  /// cut is not AV-S's below its barrier, so it cannot give way to AV-S's order at the few
  /// counts where it loses the way a greedy piece does at its barrier: held to rounding, the
  /// street-level town's refined histories, 0.4-2.4% better than AV-S at 6-93 cells on both
  /// held-out sets, were refused for losing 0.2-3.5% at 4 cells or 0.1% at 147 on one set
  /// (docs/accuracy-vs-time.md, section 5).
  double refined = 0.002;
  /// Refined pieces at counts below `low_below`, where refinement that stops at a few cells
  /// costs most (2-3.5% at 4 cells on that town) and the goals' curves do not reach.
  double refined_low = 0.02;
  size_t low_below = 16;
};

struct ValidatedMergeConfig {
  /// Sampling and stopping rule of each of the two AGVS runs; the validation run's seed is
  /// agvs.seed + 1.
  AgvsConfig agvs;
  MergeConfig merge;  ///< min_cells and progress (the prefix is chosen here)
  /// Counts scored, log-spaced from min(4, leaves) to the leaves, factor 1.25 (4, 6, 8, 11, 14,
  /// 18, ...): a small map is cut to a few cells.
  uint32_t score_from = 4;
  /// How far above AV-S's cut of the same size the held-out samples may rate a piece's counts
  /// (PieceAllowance): greedy pieces not at all, refined ones by 0.2% from 16 cells up and 2%
  /// below.
  PieceAllowance allowed;
  /// The held-out sets' disagreement at a count counted against a piece: its worst log ratio
  /// there is raised by this times its distance from the sets' mean (half the sets' difference
  /// with two sets) before it is held to the allowance. A gain one set shows and the other
  /// barely does is a tie. With 0 (until 2026-12-04), czest1tourney took a greedy history
  /// whose worse held-out set rated it 0.02% below AV-S at 709 cells and the better one 0.8%,
  /// and independent samples rated it 0.03% above AV-S at 757 (q3map2's cluster count); with
  /// 0.25 the same 71-map table changes only there and at oa_thor's quarter count (both to
  /// AV-S's own order); with 1, AV-M / AV-S at the cluster count went from a median 0.964 to
  /// 0.971 (docs/accuracy-vs-time.md). No effect with one held-out set.
  double spread_margin = 0.25;
  /// Random samples held out as well (drawn as the construction samples are, with their own
  /// seed): the evaluator's kind of PVS. Each count's log ratio is then the mean of the two
  /// held-out sets', and must be within the allowance on each. Unset: the AGVS run alone.
  std::optional<SamplerConfig> held_out_samples;
};

struct MergeStart {
  uint32_t cells = 0;    ///< greedy merging from the subdivision's cut at this many cells
  uint32_t barrier = 0;  ///< within the blocks of its cut at this many cells until there (0: none)
  double score = 0;      ///< mean log(cost / AV-S cost) on the validation PVSs (< 0: better)
  double worst = 0;      ///< the largest log(cost / AV-S cost) among the counts scored
  /// The barrier's blocks refined first (refine_blocks, on the PVSs merging decides on), the
  /// cells of the cut at `cells` being the units moved: the cut at `barrier` is then not AV-S's.
  bool refined = false;
  /// `worst` with each count's raised by the held-out sets' disagreement
  /// (ValidatedMergeConfig::spread_margin): what the choice holds to the allowance.
  double worst_with_margin = 0;
};

/// One piece of the chosen history: candidate `start`'s merges from `from` cells (a cut that
/// is AV-S's own) down to `to` cells (`start.barrier`, where its cut is AV-S's again, or the
/// end, 0). `start.cells` 1 is AV-S's own order.
struct MergePiece {
  MergeStart start;
  uint32_t from = 0, to = 0;
};

/// What a merge of the leaves chose and cost, for reports.
struct MergeSummary {
  bool validated = false;  ///< merge_validated; else greedy on the construction samples' PVSs
  /// The first piece's start (for a single candidate, the start taken; {leaf count, 0}: greedy
  /// from the leaves), with the score and worst count of the whole chosen history.
  MergeStart chosen;
  /// The chosen history, piece by piece from the leaves down (validated only): below a
  /// candidate's barrier, where its cut is AV-S's, the choice is made again for the counts
  /// below (the same choice at a smaller size), so low counts can start elsewhere.
  std::vector<MergePiece> chain;
  std::vector<MergeStart> starts;  ///< every candidate, scored (validated only)
  uint64_t merge_agvs_samples = 0, validation_agvs_samples = 0;
  uint64_t held_out_samples = 0;  ///< random samples held out (ValidatedMergeConfig::held_out_samples)
  /// The leaves' PVSs (AGVS runs included), the neighbour graph, and merging (the choice of
  /// the start included).
  double leaf_pvs_seconds = 0, neighbour_seconds = 0, merge_seconds = 0;
};

struct LeafMerge {
  MergeHistory history;  ///< its stats count the pair costs of every candidate scored
  /// Per node of the subdivision (leaves filled): the PVSs the history's are unions of (with
  /// validation, the construction samples' united with both AGVS runs').
  std::vector<std::vector<uint32_t>> leaf_pvs;
  MergeSummary summary;
};

/// The chosen history in words, piece by piece ("greedy merging from the subdivision's own
/// cut at 5000 cells, within its cut at 78 cells until there; from 78 cells: ...").
std::string describe_chain(const MergeSummary& summary);

/// `base`: the construction samples' leaf PVSs, per node of `s` (bsp/subdivision.h leaf_pvs);
/// `s` needs its cells (neighbours). Deterministic for any thread count.
LeafMerge merge_validated(const Scene& scene, const RayCaster& caster, const Subdivision& s,
                          std::vector<std::vector<uint32_t>> base, const CostModel& model,
                          const ValidatedMergeConfig& config);

/// Held-out random samples of a validated merge per construction sample. With as many as the
/// construction drew, the office's choice let cuts through that 16M independent samples a set
/// rate 2.5% worse than AV-S's (docs/accuracy-vs-time.md); with 4x none (8x chose the same), for
/// about 1.6x AV-M's build time (BENCHMARKS.md, "Decisions measured").
constexpr uint64_t kHeldOutPerConstructionSample = 4;

/// The held-out random samples of a validated merge: kHeldOutPerConstructionSample times as
/// many as the construction drew, drawn the same way, with seed construction.seed + 2000003
/// (the evaluator's default is + 1000003).
SamplerConfig held_out_sampling(const SamplerConfig& construction, uint64_t samples_drawn);

/// The leaves of `s` merged into a history from the construction samples `segments`: by
/// merge_validated when `agvs` is set (`held_out`: its random samples, held_out_sampling),
/// else greedily on the construction samples' PVSs alone. What build and compare call.
LeafMerge merge_leaves(const Scene& scene, const RayCaster& caster, const Subdivision& s, const SegmentSet& segments,
                       const SamplerConfig& held_out, const CostModel& model,
                       const std::optional<AgvsConfig>& agvs, const MergeConfig& merge);

}  // namespace viewcells
