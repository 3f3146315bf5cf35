#include "viewcells/eval/compare.h"

#include <chrono>
#include <cmath>
#include <set>

#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
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

Comparison compare_methods(const Scene& scene, const RayCaster& caster, const CompareConfig& config) {
  check_methods(config.methods);  // unknown names fail before any work
  if (config.construction.seed == config.evaluation.seed)
    throw Error("evaluation samples need their own seed (it equals the construction seed)");
  Comparison out;
  SamplingResult built = sample_segments(scene, caster, config.construction);
  out.construction = built.stats;
  if (config.evaluation_sets < 1) throw Error("at least one evaluation set is needed");
  SamplingResult eval = sample_segments(scene, caster, config.evaluation);
  out.evaluation = eval.stats;
  std::vector<SegmentSet> more;  // evaluation sets 1, 2, ...
  for (uint32_t k = 1; k < config.evaluation_sets; ++k) {
    SamplerConfig e = config.evaluation;
    e.seed += k;
    if (e.seed == config.construction.seed) throw Error("an evaluation set's seed equals the construction seed");
    SamplingResult m = sample_segments(scene, caster, e);
    out.evaluation.seconds += m.stats.seconds;  // the sampling of every set
    more.push_back(std::move(m.segments));
  }
  const uint32_t hist_cells = config.histogram_cells ? config.histogram_cells : config.max_cells;

  std::optional<Subdivision> av_s;  // shared by av-s and av-m
  double av_s_seconds = 0;
  auto build = [&](const std::string& method) {
    SubdivisionConfig sc = config.subdivision;
    sc.max_cells = config.max_cells;
    if (method == "av-s-exact") sc.exact_candidates = true;  // the paper's candidate choice beside the default
    sc.strategy = parse_split_strategy(method == "av-s-exact" ? "av-s" : method);
    sc.show_progress = config.show_progress;
    const auto t = std::chrono::steady_clock::now();
    Subdivision s = subdivide(scene, built.segments, config.model, sc);
    if (config.prepare) config.prepare(s);
    return std::make_pair(std::move(s), seconds_since(t));
  };
  for (const std::string& method : config.methods) {
    MethodResult r;
    r.method = method;
    const bool merged = method == "av-m" || method == "av-m-samples";
    Subdivision local;
    const Subdivision* s = nullptr;
    if (merged || method == "av-s") {
      if (!av_s) {
        auto [sub, secs] = build("av-s");
        av_s = std::move(sub);
        av_s_seconds = secs;
      }
      s = &*av_s;
      r.build_seconds = av_s_seconds;
    } else {
      auto [sub, secs] = build(method);
      local = std::move(sub);
      s = &local;
      r.build_seconds = secs;
    }
    r.stop_reason = s->stats.stop_reason;
    r.geometry_aligned = s->stats.geometry_aligned_reason;
    r.axis_candidates = s->stats.axis_candidates;
    r.geometry_candidates = s->stats.geometry_candidates;
    const auto t = std::chrono::steady_clock::now();
    const std::vector<std::vector<uint32_t>> pvs = evaluation_pvs(*s, eval.segments);
    if (merged) {
      MergeConfig mc;
      mc.show_progress = config.show_progress;
      LeafMerge lm = merge_leaves(scene, caster, *s, built.segments,
                                  held_out_sampling(config.construction, built.stats.samples), config.model,
                                  method == "av-m" ? config.merge_agvs : std::nullopt, mc);
      MergeHistory h = std::move(lm.history);
      r.merge = std::move(lm.summary);
      const double merge_seconds = r.merge.leaf_pvs_seconds + r.merge.neighbour_seconds + r.merge.merge_seconds;
      r.build_seconds += merge_seconds;
      out.evaluation_seconds -= merge_seconds;  // counted below with the evaluation otherwise
      const std::vector<double> node_cost = evaluated_merge_costs(scene, *s, h, pvs, config.model);
      r.evaluated = merge_history_curve(h, node_cost);
      for (const SegmentSet& e : more)
        r.evaluated_more.push_back(
            merge_history_curve(h, evaluated_merge_costs(scene, *s, h, evaluation_pvs(*s, e), config.model)));
      for (size_t cells = h.min_cells(); cells <= h.leaf_count; ++cells) {
        r.constructed.cells.push_back(static_cast<uint32_t>(cells));
        r.constructed.cost.push_back(h.cost_with(cells));
      }
      r.leaves = h.leaf_count;
      if (hist_cells >= h.min_cells() && hist_cells <= h.leaf_count)
        r.cells = merged_cells_at(h, node_cost, hist_cells);
      if (config.keep_models && method == "av-m") out.av_m = std::move(h);
    } else {
      const std::vector<double> node_cost = evaluated_bsp_costs(scene, *s, pvs, config.model);
      r.evaluated = subdivision_curve(*s, node_cost);
      for (const SegmentSet& e : more)
        r.evaluated_more.push_back(subdivision_curve(*s, evaluated_bsp_costs(scene, *s, evaluation_pvs(*s, e), config.model)));
      r.constructed.cells.push_back(1);
      r.constructed.cost.push_back(s->initial_cost);
      for (size_t k = 0; k < s->splits.size(); ++k) {
        r.constructed.cells.push_back(static_cast<uint32_t>(k + 2));
        r.constructed.cost.push_back(s->splits[k].cost_after);
      }
      r.leaves = static_cast<uint32_t>(s->leaf_count());
      if (hist_cells <= s->leaf_count()) r.cells = subdivision_cells_at(*s, node_cost, hist_cells);
    }
    out.evaluation_seconds += seconds_since(t);
    out.methods.push_back(std::move(r));
  }
  if (config.keep_models) {
    out.construction_segments = std::move(built.segments);
    out.evaluation_segments = std::move(eval.segments);
    out.av_s = std::move(av_s);
  }
  return out;
}

}  // namespace viewcells
