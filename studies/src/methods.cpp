/// Construction methods compared on the same samples (view-cell-construction paper, section 6.3).
#include "viewcells/studies/methods.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <set>

#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"
#include "viewcells/merge/merge.h"

namespace viewcells {

std::vector<uint32_t> report_cell_counts(uint32_t max) {
  std::set<uint32_t> counts;
  for (uint32_t c = 1; c <= std::min<uint32_t>(16, max); ++c) counts.insert(c);
  for (double x = 16; x <= max; x *= std::pow(10.0, 1.0 / 24)) counts.insert(static_cast<uint32_t>(std::lround(x)));
  counts.insert(max);
  std::vector<uint32_t> out;
  for (uint32_t c : counts)
    if (c >= 1 && c <= max) out.push_back(c);
  return out;
}

HalfSampleRise half_sample_rise(const MethodResult& m, uint32_t from_cells) {
  HalfSampleRise out;
  const CostCurve &all = m.evaluated, &half = m.evaluated_half;
  for (size_t i = 0, j = 0; i < all.cells.size(); ++i) {
    const uint32_t n = all.cells[i];
    while (j < half.cells.size() && half.cells[j] < n) ++j;
    if (n < from_cells || j == half.cells.size() || half.cells[j] != n || !(half.cost[j] > 0)) continue;
    const double rise = all.cost[i] / half.cost[j] - 1;
    if (!out.cells || rise > out.rise) out = {rise, n};
  }
  return out;
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

void check_methods(const std::vector<std::string>& methods) {
  if (methods.empty()) throw Error("no methods to compare");
  for (const std::string& m : methods)
    if (m != "av-m" && m != "av-m-samples" && m != "av-s-exact") parse_split_strategy(m);
}

namespace {

using Lists = std::vector<std::vector<uint32_t>>;

/// The methods' models, built from the construction samples.
struct MethodModels {
  std::vector<std::unique_ptr<Subdivision>> trees;  // distinct subdivisions (av-s, av-m share one)
  std::vector<int> tree_of;                         // per method
  std::vector<std::optional<MergeHistory>> merged;  // per method: AV-M's history
  int av_s_tree = -1;
};

/// One method's subdivision built into `models.trees`; returns its seconds.
double build_tree(const Scene& scene, const SegmentSet& segments, const CompareConfig& config,
                  const std::string& method, MethodModels& models) {
  SubdivisionConfig sc = config.subdivision;
  sc.max_cells = config.max_cells;
  if (method == "av-s-exact") sc.exact_candidates = true;  // the paper's candidate choice beside the default
  sc.strategy = parse_split_strategy(method == "av-s-exact" ? "av-s" : method);
  sc.show_progress = config.show_progress;
  const auto t = std::chrono::steady_clock::now();
  auto s = std::make_unique<Subdivision>(subdivide(scene, segments, config.model, sc));
  if (config.prepare) config.prepare(*s);
  models.trees.push_back(std::move(s));
  return seconds_since(t);
}

/// Every method built (AV-S once for the methods that share it), with its constructed curve.
MethodModels build_methods(const Scene& scene, const RayCaster& caster, const CompareConfig& config,
                           const SamplingResult& built, Comparison& out) {
  MethodModels models;
  double av_s_seconds = 0;
  for (const std::string& method : config.methods) {
    MethodResult r;
    r.method = method;
    const bool merges = method == "av-m" || method == "av-m-samples";
    if (merges || method == "av-s") {
      if (models.av_s_tree < 0) {
        av_s_seconds = build_tree(scene, built.segments, config, "av-s", models);
        models.av_s_tree = static_cast<int>(models.trees.size()) - 1;
      }
      models.tree_of.push_back(models.av_s_tree);
      r.build_seconds = av_s_seconds;
    } else {
      r.build_seconds = build_tree(scene, built.segments, config, method, models);
      models.tree_of.push_back(static_cast<int>(models.trees.size()) - 1);
    }
    const Subdivision& s = *models.trees[static_cast<size_t>(models.tree_of.back())];
    r.stop_reason = s.stats.stop_reason;
    r.geometry_aligned = s.stats.geometry_aligned_reason;
    r.axis_candidates = s.stats.axis_candidates;
    r.geometry_candidates = s.stats.geometry_candidates;
    models.merged.emplace_back();
    if (merges) {
      MergeConfig mc;
      mc.show_progress = config.show_progress;
      LeafMerge lm = merge_leaves(scene, caster, s, built.segments,
                                  held_out_sampling(config.construction, built.stats.samples), config.model,
                                  method == "av-m" ? config.merge_agvs : std::nullopt, mc);
      r.merge = std::move(lm.summary);
      r.build_seconds += r.merge.leaf_pvs_seconds + r.merge.neighbour_seconds + r.merge.merge_seconds;
      const MergeHistory& h = models.merged.back().emplace(std::move(lm.history));
      for (size_t cells = h.min_cells(); cells <= h.leaf_count; ++cells) {
        r.constructed.cells.push_back(static_cast<uint32_t>(cells));
        r.constructed.cost.push_back(h.cost_with(cells));
      }
      r.leaves = h.leaf_count;
    } else {
      r.constructed.cells.push_back(1);
      r.constructed.cost.push_back(s.initial_cost);
      for (size_t k = 0; k < s.splits.size(); ++k) {
        r.constructed.cells.push_back(static_cast<uint32_t>(k + 2));
        r.constructed.cost.push_back(s.splits[k].cost_after);
      }
      r.leaves = static_cast<uint32_t>(s.leaf_count());
    }
    out.methods.push_back(std::move(r));
  }
  return models;
}

/// Method m's evaluated curve from its tree's leaf PVSs `pvs` (per distinct tree), and with
/// `histogram` its cells at `hist_cells` into `r`.
CostCurve score_method(const Scene& scene, const CompareConfig& config, const MethodModels& models, size_t m,
                       const std::vector<Lists>& pvs, uint32_t hist_cells, bool histogram, MethodResult& r) {
  const Subdivision& s = *models.trees[static_cast<size_t>(models.tree_of[m])];
  const Lists& leaf_pvs = pvs[static_cast<size_t>(models.tree_of[m])];
  if (models.merged[m]) {
    const MergeHistory& h = *models.merged[m];
    const std::vector<double> node_cost = evaluated_merge_costs(scene, s, h, leaf_pvs, config.model);
    if (histogram && hist_cells >= h.min_cells() && hist_cells <= h.leaf_count)
      r.cells = merged_cells_at(h, node_cost, hist_cells);
    return merge_history_curve(h, node_cost);
  }
  const std::vector<double> node_cost = evaluated_bsp_costs(scene, s, leaf_pvs, config.model);
  if (histogram && hist_cells <= s.leaf_count()) r.cells = subdivision_cells_at(s, node_cost, hist_cells);
  return subdivision_curve(s, node_cost);
}

/// Evaluation set k: its samples drawn chunk by chunk, each chunk walked down every distinct
/// tree and dropped (only the leaves' object lists grow, so memory does not grow with the
/// sample count); then every method scored on it. Set 0 is also scored at half its samples
/// (rounded up to whole batches): its first half and the rest are drawn as two parts of its
/// stream.
void evaluate_set(const Scene& scene, const RayCaster& caster, const CompareConfig& config,
                  const MethodModels& models, uint32_t k, uint32_t hist_cells, Comparison& out) {
  const uint64_t samples = config.evaluation.samples, batch = config.evaluation.batch_size;
  const uint64_t half = batch ? (samples / 2 + batch - 1) / batch * batch : 0;
  SamplerConfig e = config.evaluation;
  e.seed += k;
  e.show_progress = false;  // one bar for the set, sampling and walking, over both parts
  std::vector<EvaluationPvs> gathered;  // per distinct tree: its leaves' evaluation PVSs so far
  for (const auto& t : models.trees) gathered.emplace_back(*t, scene.objects.size());
  const bool first_set = k == 0;
  Progress progress("evaluation set " + std::to_string(k + 1) + " of " + std::to_string(config.evaluation_sets),
                    samples);
  uint64_t part_drawn = 0;  // samples of the current part drawn so far
  auto use = [&](const SegmentSet& segments, uint64_t so_far) {
    const uint64_t chunk = so_far - part_drawn;
    part_drawn = so_far;
    const auto t = std::chrono::steady_clock::now();
    const std::vector<size_t> order = coherent_order(segments, segments.view_box);  // one for every tree
    for (EvaluationPvs& g : gathered) g.add(segments, order);
    if (config.keep_models && first_set) {
      out.evaluation_segments.view_box = segments.view_box;
      out.evaluation_segments.append(segments);
    }
    out.evaluation_seconds += seconds_since(t);
    if (config.show_progress) progress.advance(chunk);
  };
  SamplingStats stats;
  if (first_set && half > 0 && half < samples) {
    SamplerConfig part = e;
    part.samples = half;
    stats = sample_in_chunks(scene, caster, part, config.evaluation_chunk, use);
    const auto t = std::chrono::steady_clock::now();
    out.evaluation_half_samples = half;
    std::vector<Lists> half_lists;  // read out; the gathering goes on
    for (const EvaluationPvs& g : gathered) half_lists.push_back(g.lists());
    for (size_t m = 0; m < out.methods.size(); ++m)
      out.methods[m].evaluated_half = score_method(scene, config, models, m, half_lists, hist_cells, false,
                                                   out.methods[m]);
    out.evaluation_seconds += seconds_since(t);
    part.samples = samples - half;
    part.first_batch = e.first_batch + half / batch;
    part_drawn = 0;
    add_sampling_stats(stats, sample_in_chunks(scene, caster, part, config.evaluation_chunk, use));
  } else {
    stats = sample_in_chunks(scene, caster, e, config.evaluation_chunk, use);
  }
  if (config.show_progress) progress.finish();
  if (first_set) {
    out.evaluation = stats;
  } else {
    out.evaluation.seconds += stats.seconds;  // the sampling of every set
  }
  const auto t = std::chrono::steady_clock::now();
  std::vector<Lists> lists;
  for (EvaluationPvs& g : gathered) lists.push_back(g.take());
  gathered.clear();
  for (size_t m = 0; m < out.methods.size(); ++m) {
    CostCurve curve = score_method(scene, config, models, m, lists, hist_cells, first_set, out.methods[m]);
    if (first_set) out.methods[m].evaluated = std::move(curve);
    else out.methods[m].evaluated_more.push_back(std::move(curve));
  }
  out.evaluation_seconds += seconds_since(t);
}

}  // namespace

Comparison compare_methods(const Scene& scene, const RayCaster& caster, const CompareConfig& config) {
  check_methods(config.methods);  // unknown names fail before any work
  if (config.construction.seed == config.evaluation.seed)
    throw Error("evaluation samples need their own seed (it equals the construction seed)");
  if (config.evaluation_sets < 1) throw Error("at least one evaluation set is needed");
  for (uint32_t k = 1; k < config.evaluation_sets; ++k)
    if (config.evaluation.seed + k == config.construction.seed)
      throw Error("an evaluation set's seed equals the construction seed");
  Comparison out;
  SamplingResult built = sample_segments(scene, caster, config.construction);
  out.construction = built.stats;
  const uint32_t hist_cells = config.histogram_cells ? config.histogram_cells : config.max_cells;
  // Every method built first; then the evaluation sets.
  MethodModels models = build_methods(scene, caster, config, built, out);
  for (uint32_t k = 0; k < config.evaluation_sets; ++k) evaluate_set(scene, caster, config, models, k, hist_cells, out);
  if (config.keep_models) {
    out.construction_segments = std::move(built.segments);
    if (models.av_s_tree >= 0) out.av_s = std::move(*models.trees[static_cast<size_t>(models.av_s_tree)]);
    for (size_t m = 0; m < out.methods.size(); ++m)
      if (config.methods[m] == "av-m" && models.merged[m]) out.av_m = std::move(*models.merged[m]);
  }
  return out;
}

}  // namespace viewcells
