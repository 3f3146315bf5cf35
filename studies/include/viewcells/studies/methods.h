#pragma once
/// Comparing view cell construction methods (view-cell-construction paper, section 6.3): every
/// method builds from the same construction samples, and one evaluator scores them all on
/// independent evaluation samples.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/eval/evaluate.h"
#include "viewcells/validated/merge.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"

namespace viewcells {

struct CompareConfig {
  /// av-m, av-m-samples, av-s, av-s-exact (AV-S with SubdivisionConfig::exact_candidates),
  /// kd-casm, kd-lasm, kd-vt, kd-vt-star, bsp
  std::vector<std::string> methods = {"av-m", "av-m-samples", "av-s", "kd-casm", "kd-lasm", "kd-vt", "kd-vt-star", "bsp"};
  uint32_t max_cells = 1000;
  SamplerConfig construction;  ///< samples for building
  SamplerConfig evaluation;    ///< independent samples for scoring (own seed, more of them)
  /// Independent evaluation sets: set k (from 0) draws as `evaluation` does with seed
  /// evaluation.seed + k. Every method is scored on each; MethodResult::evaluated is set 0's.
  /// Their disagreement is the evaluator's own noise.
  uint32_t evaluation_sets = 1;
  CostModel model;
  SubdivisionConfig subdivision;  ///< shared settings (strategy is set per method)
  uint32_t histogram_cells = 0;   ///< cell count of the histograms (0: max_cells)
  bool show_progress = true;
  /// Optional: applied to every subdivision once built, before merging and evaluation (e.g.
  /// weight_by_view_space, when the view space is not the whole box).
  std::function<void(Subdivision&)> prepare;
  /// AV-M: merging validated by AGVS runs over the leaves with this config
  /// (validated/merge.h). Unset: AV-M is greedy merging of the leaves on the construction
  /// samples' PVSs alone, which av-m-samples always is.
  std::optional<AgvsConfig> merge_agvs;
  /// Samples of an evaluation set drawn at a time: each chunk is walked down every tree and
  /// dropped, so the evaluation's memory is about one chunk's plus the leaves' object lists,
  /// whatever the sample count. The result does not depend on it.
  uint64_t evaluation_chunk = 1'000'000;
  /// Keep the segments, the AV-S subdivision and the AV-M merge history in the Comparison.
  bool keep_models = false;
};

struct MethodResult {
  std::string method;
  CostCurve evaluated;          ///< c(S) on the evaluation samples along the method's order
  std::vector<CostCurve> evaluated_more;  ///< the same on evaluation sets 1, 2, ... (evaluation_sets)
  /// The same as `evaluated` from the first Comparison::evaluation_half_samples samples of its
  /// set (about half): what the second half added is how far the evaluator is from converged
  /// for this method (sampled PVSs only miss objects, so costs only rise with more samples).
  CostCurve evaluated_half;
  CostCurve constructed;        ///< the method's own estimate (construction samples)
  std::vector<CellCost> cells;  ///< evaluated cells at the histogram cell count (if reached)
  uint32_t leaves = 0;          ///< cells the method produced
  double build_seconds = 0;     ///< subdivision (and merging), without sampling
  MergeSummary merge;  ///< AV-M: what its merge chose, and its seconds (part of build_seconds)
  std::string stop_reason;
  std::string geometry_aligned;  ///< whether geometry-aligned candidates were used, and why
  uint64_t axis_candidates = 0, geometry_candidates = 0;  ///< candidate planes evaluated
};

struct Comparison {
  std::vector<MethodResult> methods;
  SamplingStats construction, evaluation;
  double evaluation_seconds = 0;
  uint64_t evaluation_half_samples = 0;  ///< see MethodResult::evaluated_half (0: not scored)
  // With CompareConfig::keep_models:
  SegmentSet construction_segments, evaluation_segments;
  std::optional<Subdivision> av_s;      ///< when av-s or av-m was built
  std::optional<MergeHistory> av_m;     ///< when av-m was built (over av_s's leaves)
};

/// Throws Error for an empty list or a name that is not one of the methods.
void check_methods(const std::vector<std::string>& methods);

/// Builds every method of config.methods and evaluates it. Throws Error for unknown methods.
Comparison compare_methods(const Scene& scene, const RayCaster& caster, const CompareConfig& config);

/// How much the second half of the first evaluation set raised a method's cost: the largest
/// evaluated / evaluated_half - 1 over the report's counts from `from_cells` on (and where).
/// 0 at 0 cells when the comparison scored no half.
struct HalfSampleRise {
  double rise = 0;
  uint32_t cells = 0;
};
HalfSampleRise half_sample_rise(const MethodResult& m, uint32_t from_cells = 16);

/// Cell counts to report a curve at: every count up to 16, then about 24 per decade, and the
/// last one; all <= max.
std::vector<uint32_t> report_cell_counts(uint32_t max);

}  // namespace viewcells
