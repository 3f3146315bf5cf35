/// `viewcells compare`'s summary.json (studies/compare.h), with the pipeline's report parts.
#include <cmath>
#include <nlohmann/json.hpp>

#include "pipeline/report_parts.h"
#include "viewcells/q3/level.h"
#include "viewcells/studies/compare.h"

namespace viewcells::studies {

using namespace pipeline::report_detail;

namespace {

json compare_methods_json(const Comparison& cmp) {
  json methods = json::array();
  for (const MethodResult& m : cmp.methods) {
    const uint32_t last = m.evaluated.cells.back();
    methods.push_back({{"method", m.method},
                       {"cells", m.leaves},
                       {"build_seconds", m.build_seconds},
                       {"stop_reason", m.stop_reason},
                       {"geometry_aligned", m.geometry_aligned},
                       {"axis_candidates_evaluated", m.axis_candidates},
                       {"geometry_candidates_evaluated", m.geometry_candidates},
                       {"evaluated_cost_at_most_cells", m.evaluated.at(last)},
                       {"constructed_cost_at_most_cells", m.constructed.at(last)}});
    if (cmp.evaluation_half_samples) {
      const HalfSampleRise rise = half_sample_rise(m);
      if (rise.cells)
        methods.back()["evaluator_second_half_rise"] = {{"largest", rise.rise},
                                                        {"at_cells", rise.cells},
                                                        {"from_cells", 16},
                                                        {"first_half_samples", cmp.evaluation_half_samples}};
    }
    if (m.method == "av-m" || m.method == "av-m-samples") {
      const MergeSummary& v = m.merge;
      methods.back()["merge"] = {{"leaf_pvs_seconds", v.leaf_pvs_seconds},
                                 {"neighbour_graph_seconds", v.neighbour_seconds},
                                 {"merge_seconds", v.merge_seconds},
                                 {"leaf_agvs_samples", v.merge_agvs_samples + v.validation_agvs_samples},
                                 {"held_out_random_samples", v.held_out_samples},
                                 {"greedy_from_cells", v.chosen.cells},
                                 {"barrier_cells", v.chosen.barrier},
                                 {"starts_scored", starts_json(v.starts)},
                                 {"chain", chain_json(v)}};
    }
  }
  return methods;
}

json q3_summary(const Q3Comparison& q, const Q3Map& map) {
  const bool reached = std::isfinite(q.avm_cost_at_clusters);
  json causes = json::object();
  for (const auto& [cause, n] : q.excluded_by_cause) causes[cause] = n;
  return {{"map", map.path},
          {"clusters", q.cluster_count},
          {"q3map2_cost", q.clusters.cost},
          {"av_m_cost_at_clusters", reached ? json(q.avm_cost_at_clusters) : json(nullptr)},
          {"av_m_cost_ratio", reached ? json(q.avm_cost_at_clusters / q.clusters.cost) : json(nullptr)},
          {"av_m_cells_to_match", q.avm_cells_to_match ? json(q.avm_cells_to_match) : json(nullptr)},
          {"pvs_size_ratio", q.mean_pvs_ratio},
          {"pvs_entries", {{"ours", q.ours_entries}, {"q3map2", q.q3_entries}}},
          {"excluded_but_seen", q.excluded.size()},
          {"excluded_by_cause", causes},
          {"storage_bytes",
           {{"q3map2_rows", q.q3_row_bytes},
            {"q3map2_leaf_surface_lists", q.q3_leaf_surface_bytes},
            {"ours_compressed", q.ours_compressed_bytes},
            {"ours_rle_rows", q.ours_rle_bytes}}},
          {"build_seconds", q.build_seconds}};
}

}  // namespace

std::string report_json(const CompareRunResult& r) {
  const CompareConfig& config = r.compared;
  const Comparison& cmp = r.comparison();
  json summary = {
      {"command", "compare"},
      {"scene", scene_summary(*r.loaded.scene)},
      {"settings",
       {{"methods", config.methods},
        {"max_cells", config.max_cells},
        {"construction_samples", config.construction.samples},
        {"construction_seed", config.construction.seed},
        {"evaluation_samples", config.evaluation.samples},
        {"evaluation_seed", config.evaluation.seed},
        {"evaluation_sets", config.evaluation_sets},
        {"histogram_cells", config.histogram_cells ? config.histogram_cells : config.max_cells},
        {"cost_model", {{"a", config.model.a}, {"b", config.model.b}, {"c", 0}}},
        {"axis_candidates", config.subdivision.max_axis_candidates},
        {"axis_candidates_choice", config.subdivision.exact_candidates ? "exact" : "fast"},
        {"ga_candidates", config.subdivision.ga_candidates},
        {"geometry_aligned", r.config.geometry_aligned_off ? "off" : "auto"},
        {"robust_ray_casting", r.config.scene.robust},
        {"merge_pvs", config.merge_agvs ? "agvs" : "samples"},
        {"merge_agvs_samples_per_run", config.merge_agvs ? json(config.merge_agvs->max_samples) : json(nullptr)},
        {"merge_agvs_pixel_error", config.merge_agvs ? json(config.merge_agvs->pixel_error) : json(nullptr)},
        {"threads", r.threads}}},
      {"effects",
       {{"empty_space_detection", effect(cmp.construction.empty_space.enabled, cmp.construction.empty_space.reason)},
        {"pixel_cost_term", effect(false, "c = 0: the comparison uses r(o) = max(a, b t)")}}},
      {"methods", compare_methods_json(cmp)},
      {"view_space", r.loaded.view_space->describe()},
      {"timings",
       {{"load_seconds", r.loaded.load_seconds},
        {"bvh_build_seconds", r.loaded.bvh_seconds},
        {"construction_sampling_seconds", cmp.construction.seconds},
        {"evaluation_sampling_seconds", cmp.evaluation.seconds},
        {"evaluation_seconds", cmp.evaluation_seconds}}}};
  if (r.q3) summary["q3map2"] = q3_summary(*r.q3, *q3_map_of(r.loaded.level.get()));
  return text(summary);
}

}  // namespace viewcells::studies
