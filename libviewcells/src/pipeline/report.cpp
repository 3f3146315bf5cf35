// The pipeline's JSON reports (pipeline/report.h): the only place they are assembled.
#include "viewcells/pipeline/report.h"

#include <nlohmann/json.hpp>

#include <cmath>

#include "viewcells/core/cluster.h"
#include "viewcells/core/format.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/binary_file.h"

namespace viewcells::pipeline {

namespace {

using nlohmann::json;

json to_json(const Vec3& v) { return json::array({v.x, v.y, v.z}); }
json to_json(const Box3& b) { return {{"min", to_json(b.lo)}, {"max", to_json(b.hi)}}; }
/// NaN (not known) as JSON null.
json number_or_null(double v) { return std::isnan(v) ? json(nullptr) : json(v); }
json effect(bool enabled, const std::string& reason) { return {{"enabled", enabled}, {"reason", reason}}; }

/// Reports say which Embree ISA cast their rays: results are bit-identical only for the same one.
/// On several MPI ranks they also say how many, and what the ranks exchanged (rank 0's side).
std::string text(json j) {
  if (j.is_object()) {
    j["embree_isa"] = embree_isa();
    if (cluster::size() > 1) {
      const cluster::Traffic& t = cluster::traffic();
      j["cluster"] = {{"ranks", cluster::size()},
                      {"exchanges", t.calls},
                      {"bytes_sent", t.bytes_sent},
                      {"bytes_received", t.bytes_received},
                      {"exchange_seconds", t.seconds}};
    }
  }
  return j.dump(2) + "\n";
}

json scene_summary(const Scene& s) {
  size_t closed = 0, solid = 0;
  for (const auto& o : s.objects) {
    closed += o.closed;
    solid += o.solid();
  }
  return {{"source", s.source},
          {"triangles", s.triangle_count()},
          {"degenerate_triangles_dropped", s.degenerate_dropped},
          {"objects", s.object_count()},
          {"grouping", to_string(s.grouping)},
          {"bounds", to_json(s.bounds)},
          {"closed_objects", closed},
          {"solid_objects", solid},
          {"all_solid", s.all_solid},
          {"surface_area", s.surface_area},
          {"non_axis_aligned_area_share", s.non_axis_aligned_share()}};
}

json map_summary(const MapInfo& m) {
  const Q3MeshStats& st = m.mesh;
  return {{"version", m.map.version},
          {"leaves", m.map.leaves.size()},
          {"solid_leaves", m.solid_leaves},
          {"surfaces", {{"opaque", st.surfaces[0]}, {"sky", st.surfaces[1]}, {"non_occluding", st.surfaces[2]},
                        {"skipped", st.surfaces[3]}, {"patches", st.patches}}},
          {"brush_hulls", st.brush_hulls},
          {"clusters", m.map.cluster_count},
          {"cluster_row_bytes", m.map.cluster_bytes},
          {"spawn_points", st.spawn_points}};
}

json sampling_effects(const SamplingRun& s) {
  const SamplingStats& st = s.result.stats;
  const bool robust = s.loaded.source.robust;
  return {{"empty_space_detection", effect(st.empty_space.enabled, st.empty_space.reason)},
          {"embree_robust_mode",
           effect(robust, robust ? "enabled by default: fewer rays slip through shared edges"
                                 : "disabled by --fast: faster, but rays may slip through shared edges")},
          {"see_through_objects",
           effect(st.see_through_objects > 0,
                  st.see_through_objects
                      ? std::to_string(st.see_through_objects) +
                            " objects are seen through (water, glass, fog): they stop no ray, and every segment "
                            "crossing one sees it"
                      : std::string("every object occludes"))},
          {"restricted_view_space", effect(static_cast<bool>(s.config.view_space), s.loaded.view_space)}};
}

json sampling_counts(const SamplingRun& s) {
  const SamplingStats& st = s.result.stats;
  uint64_t objects_hit = 0, max_per_object = 0;
  for (uint64_t n : st.segments_per_object) {
    objects_hit += n > 0;
    max_per_object = std::max(max_per_object, n);
  }
  return {{"samples", st.samples},
          {"rays", st.rays},
          {"recast_rays", st.recast_rays},
          {"valid_segments", st.valid_segments},
          {"missed_both", st.missed_both},
          {"stuck_in_solid", st.stuck_in_solid},
          {"outside_view_box", st.outside_view_box},
          {"two_sided_samples", st.two_sided_samples},
          {"rejected_origins", st.rejected_origins},
          {"see_through_objects", st.see_through_objects},
          {"see_through_segments", st.see_through_segments},
          {"see_through_rays", st.see_through_rays},
          {"objects_hit", objects_hit},
          {"objects_never_hit", s.loaded.scene->object_count() - objects_hit},
          {"max_segments_per_object", max_per_object},
          {"segments_per_object", st.segments_per_object}};
}

/// What sample and build share: the scene, sampling settings, effects, counts and timings.
json sampling_report(const SamplingRun& s) {
  const SamplingStats& st = s.result.stats;
  const SamplerConfig& c = s.config;
  json report;
  report["scene"] = scene_summary(*s.loaded.scene);
  report["settings"] = {{"samples", c.target_segments ? json(nullptr) : json(c.samples)},
                        {"target_segments", c.target_segments ? json(c.target_segments) : json(nullptr)},
                        {"seed", c.seed},
                        {"threads", s.threads},
                        {"object_grouping", to_string(s.loaded.scene->grouping)},
                        {"view_box", to_json(st.view_box)},
                        {"view_box_source", st.view_box_from_scene ? "scene bounds"
                                            : (s.loaded.map && !s.view_box_given ? "the map's non-solid leaves"
                                                                                 : "user (--view-box)")},
                        {"view_space", s.loaded.view_space},
                        {"ray_caster", s.loaded.caster->name()},
                        {"max_recasts", c.max_recasts},
                        {"batch_size", c.batch_size}};
  report["effects"] = sampling_effects(s);
  report["counts"] = sampling_counts(s);
  report["timings"] = {{"load_seconds", s.loaded.load_seconds},
                       {"bvh_build_seconds", s.loaded.bvh_seconds},
                       {"sampling_seconds", st.seconds},
                       {"segments_per_second", st.valid_segments / st.seconds},
                       {"samples_per_second", st.samples / st.seconds},
                       {"rays_per_second", st.rays / st.seconds}};
  return report;
}

json cost_curve(const Subdivision& sub) {
  json curve = json::array();
  for (size_t cells = 1; cells <= sub.leaf_count(); cells *= 2)
    curve.push_back({{"cells", cells}, {"cost", cells == 1 ? sub.initial_cost : sub.splits[cells - 2].cost_after}});
  return curve;
}

json starts_json(const std::vector<MergeStart>& starts) {
  json out = json::array();
  for (const MergeStart& st : starts)
    out.push_back({{"cells", st.cells},
                   {"barrier", st.barrier},
                   {"refined", st.refined},
                   {"score", st.score},
                   {"worst", st.worst},
                   {"worst_with_margin", st.worst_with_margin}});
  return out;
}

json chain_json(const MergeSummary& v) {
  json out = json::array();
  for (const MergePiece& p : v.chain)
    out.push_back({{"from_cells", p.from}, {"to_cells", p.to}, {"greedy_from_cells", p.start.cells},
                   {"barrier_cells", p.start.barrier}, {"refined", p.start.refined}});
  return out;
}

json merge_summary(const MergeHistory& h) {
  json merged = json::array();
  for (size_t cells = 1; cells <= h.leaf_count; cells *= 2)
    if (cells >= h.min_cells()) merged.push_back({{"cells", cells}, {"cost", h.cost_with(cells)}});
  return {{"cells_from", h.leaf_count},
          {"cells_to", h.min_cells()},
          {"cost_at_power_of_two_cells", merged},
          {"pair_costs_evaluated", h.stats.evaluations},
          {"stale_entries_skipped", h.stats.stale}};
}

json build_effects(const BuildResult& r) {
  const CostModel& model = r.model;
  const SubdivisionConfig& config = r.subdivision_config;
  const Subdivision& sub = r.file.subdivision;
  json e;
  e["geometry_aligned_candidates"] = effect(sub.stats.geometry_aligned, sub.stats.geometry_aligned_reason);
  e["pixel_cost_term"] = effect(model.pixel_term(), model.describe_pixel_term());
  e["viewpoint_density"] =
      !r.play_space.empty() ? effect(true, "the play space (--play-space, bake's default on a Quake 3 map): p(i) is the "
                                           "share of " + r.play_space + " in the cell")
      : config.density.enabled
          ? effect(true, "--density-band: weight 1 for " + fmt(config.density.lo, 2) + " <= z <= " +
                             fmt(config.density.hi, 2) + ", " + fmt(config.density.outside, 3) + " elsewhere")
          : effect(false, "uniform: p(i) = V_i / V (no --density-band)");
  e["merging"] = !r.merge ? effect(false, "--no-merge")
                 : r.merge_summary.validated
                     ? effect(true, "default: merged on the leaves' PVSs from the construction samples and an AGVS run, "
                                    "from the subdivision's cut a second, held-out AGVS run chose")
                     : effect(true, "--merge-pvs samples: greedy merging on the construction samples' PVSs");
  return e;
}

}  // namespace

std::string report_json(const SceneInfo& info) {
  json j = scene_summary(info.scene);
  j["empty_space_detection"] = effect(info.empty_space.enabled, info.empty_space.reason);
  json objects = json::array();
  for (const ObjectInfo& o : info.scene.objects)
    objects.push_back({{"name", o.name},
                       {"triangles", o.triangle_count},
                       {"bounds", to_json(o.bounds)},
                       {"closed", o.closed},
                       {"oriented", o.oriented},
                       {"solid", o.solid()}});
  j["object_list"] = std::move(objects);
  if (info.map) j["quake3"] = map_summary(*info.map);
  return text(j);
}

std::string report_json(const SampleResult& r) {
  json report = sampling_report(r.run);
  report["command"] = "sample";
  report["timings"]["write_seconds"] = r.write_seconds;
  if (r.raw) {
    const SamplingStats& st = r.run.result.stats;
    const double raw_rate = r.raw->rays / r.raw->seconds;
    const double seg_rate = st.valid_segments / st.seconds;
    report["timings"]["raw_rays"] = r.raw->rays;
    report["timings"]["raw_seconds"] = r.raw->seconds;
    report["timings"]["raw_rays_per_second"] = raw_rate;
    report["timings"]["segments_per_second_over_half_raw_rays_per_second"] = seg_rate / (0.5 * raw_rate);
  }
  return text(report);
}

std::string report_json(const BuildResult& r) {
  const Subdivision& sub = r.file.subdivision;
  const CostModel& model = r.model;
  json report = sampling_report(r.sampling);
  report["command"] = "build";
  json& settings = report["settings"];
  settings["max_cells"] = r.subdivision_config.max_cells;
  settings["axis_candidates_per_axis"] = r.subdivision_config.max_axis_candidates;
  settings["axis_candidates_choice"] = r.subdivision_config.exact_candidates ? "exact" : "fast";
  settings["ga_candidates"] = r.subdivision_config.ga_candidates;
  settings["min_reduction"] = r.subdivision_config.min_reduction;
  settings["cost_model"] = {{"a", model.a}, {"b", model.b}, {"c", model.c}};
  if (model.pixel_term())
    settings["cost_model"]["screen"] = {
        {"width", model.screen_width}, {"height", model.screen_height}, {"fov_degrees", model.fov_degrees}};
  const json effects = build_effects(r);
  for (const auto& [key, value] : effects.items()) report["effects"][key] = value;
  report["subdivision"] = {{"cells", sub.leaf_count()},
                           {"initial_cost", sub.initial_cost},
                           {"final_cost", sub.cost()},
                           {"cost_at_power_of_two_cells", cost_curve(sub)},
                           {"axis_candidates_evaluated", sub.stats.axis_candidates},
                           {"geometry_candidates_evaluated", sub.stats.geometry_candidates},
                           {"geometry_candidates_on_all_parts", sub.stats.geometry_full_passes},
                           {"segment_parts_evaluated", sub.stats.parts_evaluated},
                           {"sliver_splits_refused", sub.stats.slivers_refused},
                           {"splits_undone", sub.stats.splits_undone},
                           {"stop_reason", sub.stats.stop_reason}};
  report["final_cost"] = sub.cost();
  if (r.file.history) {
    report["merge"] = merge_summary(*r.file.history);
    const MergeSummary& v = r.merge_summary;
    report["merge"]["pvs"] = v.validated ? "construction samples and two AGVS runs" : "construction samples";
    report["merge"]["greedy_from_cells"] = v.chosen.cells;
    report["merge"]["barrier_cells"] = v.chosen.barrier;
    if (v.validated) {
      report["merge"]["starts_scored"] = starts_json(v.starts);
      report["merge"]["chain"] = chain_json(v);
      report["merge"]["held_out"] = {{"mean_log_cost_ratio_to_av_s", v.chosen.score},
                                     {"worst_log_cost_ratio_to_av_s", v.chosen.worst}};
      report["merge"]["agvs_samples"] = {{"merge", v.merge_agvs_samples}, {"validation", v.validation_agvs_samples}};
      report["merge"]["held_out_random_samples"] = v.held_out_samples;
    }
    report["timings"]["leaf_pvs_seconds"] = v.leaf_pvs_seconds;
    report["timings"]["neighbour_graph_seconds"] = v.neighbour_seconds;
    report["timings"]["merge_seconds"] = v.merge_seconds;
  }
  report["timings"]["subdivision_seconds"] = sub.stats.seconds;
  report["timings"]["write_seconds"] = r.write_seconds;
  report["timings"]["export_seconds"] = r.export_seconds;
  return text(report);
}

std::string report_json(const ExtractResult& r) {
  const MergeHistory& h = *r.file.history;
  const ViewCellSet& set = r.set;
  const std::vector<int32_t> leaves = r.file.subdivision.leaves();
  json cells = json::array();
  for (size_t i = 0; i < set.cells.size(); ++i) {
    const MergeNode& n = h.nodes[set.cells[i]];
    json bsp_leaves = json::array();
    for (uint32_t l : h.leaves_under(set.cells[i])) bsp_leaves.push_back(leaves[l]);
    cells.push_back({{"id", i},
                     {"merge_node", set.cells[i]},
                     {"bsp_leaves", bsp_leaves},
                     {"volume", n.volume},
                     {"bounds", to_json(n.bounds)},
                     {"pvs_size", n.pvs_size},
                     {"pvs_cost", n.pvs_cost}});
  }
  return text({{"command", "extract"},
               {"input", r.input},
               {"rule", set.rule},
               {"cells", set.cells.size()},
               {"cost", set.cost},
               {"cost_of_elementary_cells", h.initial_cost},
               {"cost_ratio", set.cost / h.initial_cost},
               {"pvs_entries", set.pvs_entries},
               {"approximate_pvs_bytes", set.pvs_bytes},
               {"view_cells", cells}});
}

std::string report_json(const CompressResult& r) {
  json report = {{"command", "compress"},
                 {"input", r.input},
                 {"output", r.output},
                 {"rule", r.rule},
                 {"cells", r.cells},
                 {"objects", r.objects},
                 {"hierarchy_nodes", r.hierarchy_nodes},
                 {"entries_before", r.entries_before},
                 {"entries_after", r.entries_after},
                 {"entry_ratio", r.entries_before ? double(r.entries_after) / r.entries_before : 1.0},
                 {"raw_bytes_before", 4 * r.entries_before},
                 {"raw_bytes_after", 4 * r.entries_after},
                 {"list_bytes_before", r.list_bytes_before},
                 {"list_bytes_after", r.list_bytes_after},
                 {"file_bytes", r.file_bytes},
                 {"seconds", r.seconds}};
  if (!r.flat.empty())
    report["flat"] = {{"file", r.flat},
                      {"bit_row_bytes", r.flat_bit_row_bytes},
                      {"run_length_bytes", r.flat_run_length_bytes},
                      {"file_bytes", r.flat_file_bytes}};
  return text(report);
}

namespace {

json measure_json(const std::optional<PixelErrorMeasure>& m, uint32_t size) {
  return m ? json{{"pixels", m->pixels}, {"share", m->share}, {"cameras", m->cameras},
                  {"cameras_with_wrong_pixels", m->cameras_wrong}, {"camera_size", size}, {"fov_degrees", 90}}
           : json(nullptr);
}

json measured_curve(const std::vector<MeasuredPoint>& curve) {
  json out = json::array();
  for (const MeasuredPoint& p : curve)
    out.push_back({{"samples", p.samples}, {"rays", p.rays}, {"seconds", p.seconds}, {"mean_pvs", p.mean_pvs},
                   {"estimated_pixel_error", number_or_null(p.estimated)}, {"measured_pixels", p.measured.pixels},
                   {"measured_median_pixels", p.measured.median_pixels},
                   {"measured_p99_pixels", p.measured.p99_pixels},
                   {"measured_worst_pixels", p.measured.worst_pixels},
                   {"cameras_with_wrong_pixels", p.measured.cameras_wrong},
                   {"frames_with_wrong_pixels_share",
                    p.measured.wrong_frame_share()},
                   {"eta_seconds", number_or_null(p.eta_seconds)}});
  return out;
}

json agvs_distributions(const AgvsStats& st) {
  json dists = json::array();
  for (int d = 0; d < AgvsStats::kDistributions; ++d)
    dists.push_back({{"distribution", to_string(static_cast<AgvsDistribution>(d))},
                     {"samples", st.dist_samples[d]},
                     {"rays", st.dist_rays[d]},
                     {"contribution", st.dist_contribution[d]},
                     {"last_probability", st.dist_probability[d]}});
  return dists;
}

json agvs_curve(const AgvsStats& st, size_t references) {
  json curve = json::array();
  for (const AgvsPoint& p : st.curve)
    curve.push_back({{"seconds", p.seconds}, {"samples", p.samples}, {"rays", p.rays}, {"mean_pvs_size", p.mean_pvs},
                     {"pixel_error", number_or_null(p.pixel_error)},
                     {"pixel_error_bound", number_or_null(p.pixel_error_bound)},
                     {"camera_rays", p.camera_rays},
                     {"wrong_camera_rays", p.wrong_camera_rays},
                     {"covered", json(std::vector<uint64_t>(p.covered, p.covered + references))}});
  return curve;
}

json agvs_view_space(bool restricted, bool play = false) {
  return effect(restricted, play         ? "the play space (--play-space, bake's default on a Quake 3 map): AGVS's "
                                           "points are drawn in its leaves (those reachable from the spawn points with "
                                           "a point at most 112 units above a walkable floor)"
                            : restricted ? "a Quake 3 map: AGVS's points are drawn in its non-solid space"
                                         : "AGVS's points are drawn in the whole view box");
}

json pvs_effects(const PvsResult& r) {
  const AgvsStats& st = r.stats;
  const bool agvs = r.agvs.method == AgvsMethod::kAgvs;
  return {{"empty_space_detection", effect(st.empty_space.enabled, st.empty_space.reason)},
          {"restricted_view_space", agvs_view_space(static_cast<bool>(r.agvs.view_space))},
          {"silhouette_mutation", effect(agvs, agvs ? "part of the AGVS mixture" : "AGVS only")},
          {"visibility_filter",
           effect(r.filtering, r.filtering ? "asked for (--filter / --filter-neighbours): the written PVSs are "
                                             "extended by objects likely visible given the sampling density"
                                           : "not asked for: the written PVSs are the sampled ones")}};
}

}  // namespace

std::string report_json(const PvsResult& r) {
  const PvsConfig& c = r.config;
  const AgvsStats& st = r.stats;
  const json filter = r.filtering ? json{{"object_space", c.filter_object_space},
                                         {"k", c.filter.k},
                                         {"view_neighbours", c.filter.view_neighbours},
                                         {"mean_pvs_size_unfiltered", r.mean_pvs},
                                         {"mean_pvs_size_filtered", r.mean_written},
                                         {"measured_pixel_error_unfiltered",
                                          measure_json(r.measured_unfiltered, c.measure_size)}}
                                  : json(nullptr);
  const json edit = r.edit ? json{{"edited_from", c.edited_from},
                                  {"deleted_objects", r.edit->deleted},
                                  {"inserted_objects", r.edit->inserted},
                                  {"entries_of_deleted_objects", r.edit->removed_deleted},
                                  {"entries_in_penumbrae", r.edit->removed_penumbra},
                                  {"cells_emptied", r.edit->cells_cleared}}
                           : json(nullptr);
  return text({{"command", "pvs"},
               {"input", c.hierarchy_path},
               {"scene", c.scene_path},
               {"output", c.output},
               {"method", to_string(r.agvs.method)},
               {"cells", r.cells},
               {"rule", r.rule},
               {"settings",
                {{"seed", r.agvs.seed}, {"batch_size", r.agvs.batch_size}, {"mutation_lanes", r.agvs.mutation_lanes},
                 {"resolution", r.agvs.resolution},
                 {"threads", r.threads}, {"window_p", r.agvs.window_p}, {"window_k", r.agvs.window_k}}},
               {"effects", pvs_effects(r)},
               {"filter", filter},
               {"edit", edit},
               {"samples", st.samples},
               {"rays", st.rays},
               {"seconds", st.seconds},
               {"setup_seconds", r.setup_seconds},
               {"samples_per_second", st.seconds > 0 ? st.samples / st.seconds : 0.0},
               {"mean_pvs_size", r.mean_pvs},
               {"mean_pvs_size_written", r.mean_written},
               {"pvs_entries", r.pvs_entries},
               {"estimated_pixel_error", number_or_null(r.pixel_error)},
               {"pixel_error_bound", number_or_null(r.pixel_error_bound)},
               {"estimator_window_rays", st.window_rays},
               {"measured_pixel_error", measure_json(r.measured, c.measure_size)},
               {"measuring_cameras", r.camera_rule.empty() ? json(nullptr) : json(r.camera_rule)},
               {"measured_curve", measured_curve(r.measured_curve)},
               {"stop_reason", st.stop_reason},
               // Where this run's time went (resumed: this run's part only).
               {"phases",
                {{"draw_seconds", st.draw_seconds},
                 {"cast_seconds", st.cast_seconds},
                 {"apply_seconds", st.apply_seconds},
                 {"mutation_seconds", st.mutation_seconds},
                 {"segments", st.segments},
                 {"pierced_cells", st.pierced_cells}}},
               {"distributions", agvs_distributions(st)},
               {"curve", agvs_curve(st, c.references.size())}});
}

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
      {"view_space", r.loaded.view_space},
      {"timings",
       {{"load_seconds", r.loaded.load_seconds},
        {"bvh_build_seconds", r.loaded.bvh_seconds},
        {"construction_sampling_seconds", cmp.construction.seconds},
        {"evaluation_sampling_seconds", cmp.evaluation.seconds},
        {"evaluation_seconds", cmp.evaluation_seconds}}}};
  if (r.q3) summary["q3map2"] = q3_summary(*r.q3, *r.loaded.map);
  return text(summary);
}

std::string report_json(const BakeResult& r) {
  const BakeConfig& c = r.config;
  const AgvsStats& st = r.agvs;
  json budget = c.memory ? json{{"memory_bytes", c.memory}, {"counts", c.memory_of_lists ? "lists" : "file"}}
                         : json{{"cells", c.cells}};
  return text({{"command", "bake"},
               {"scene", c.scene.path},
               {"output", c.output},
               {"budget", budget},
               {"settings",
                {{"construction_samples", c.sampling.samples},
                 {"seed", c.sampling.seed},
                 {"elementary_cells", r.elementary_cells},
                 {"play_space", c.subdivision.play_space},
                 {"pixel_error", c.agvs.pixel_error},
                 {"measured_error", c.measured_error},
                 {"holes", c.holes},
                 {"measure_cameras", c.measure_cameras},
                 {"measure_frame", {{"width", c.frame.width}, {"height", c.frame.height}}},
                 {"max_seconds", c.agvs.max_seconds},
                 {"max_samples", c.agvs.max_samples},
                 {"agvs_batch_size", c.agvs.batch_size},
                 {"agvs_mutation_lanes", c.agvs.mutation_lanes},
                 {"work_dir", c.work_dir},
                 {"threads", r.threads},
                 {"cost_model", {{"a", c.model.a}, {"b", c.model.b}, {"c", c.model.c}}}}},
               {"effects",
                {{"hierarchy_reused",
                  effect(r.hierarchy_reused, r.hierarchy_reused ? "the work directory holds one for these settings"
                                                                : "built: none kept for these settings")},
                 {"agvs_resumed",
                  effect(r.agvs_resumed, r.agvs_resumed ? "continued from the work directory's state"
                                                        : "started from no samples")},
                 {"budget_coarsened",
                  effect(r.cells < r.agvs_cells, r.cells < r.agvs_cells
                                                     ? "the file of " + std::to_string(r.agvs_cells) +
                                                           " cells exceeded the memory budget: merged cells' PVSs "
                                                           "are the unions of their parts"
                                                     : "the file fits the budget as sampled")},
                 {"empty_space_detection", effect(st.empty_space.enabled, st.empty_space.reason)},
                 {"restricted_view_space", agvs_view_space(r.agvs_in_view_space, c.subdivision.play_space)},
                 {"frame_samples",
                  effect(c.frame_samples > 0,
                         c.frame_samples > 0
                             ? std::to_string(r.frame_sample_cameras) + " frames of " + std::to_string(c.sample_frame.width) +
                                   "x" + std::to_string(c.sample_frame.height) + " from cameras of their own seed added " +
                                   std::to_string(r.frame_sample_entries) + " PVS entries in " +
                                   fmt(r.frame_sample_seconds, 2) + " s (--frame-samples)"
                             : "not asked for (--frame-samples)")},
                 {"near_samples",
                  effect(c.near.rays_per_object > 0,
                         c.near.rays_per_object > 0
                             ? std::to_string(r.near.tested) + " (cell, neighbouring object) pairs tested with " +
                                   std::to_string(r.near.rays) + " rays from " + std::to_string(r.near_eyes) +
                                   " viewpoints added " + std::to_string(r.near.added) + " PVS entries in " +
                                   fmt(r.near_seconds, 2) + " s (--near-samples)"
                             : "not asked for (--near-samples)")}}},
               {"scene_fingerprint", r.scene_fingerprint},
               {"objects", r.object_count},
               {"cells", r.cells},
               {"rule", r.rule},
               {"file_bytes", r.file_bytes},
               {"list_bytes", r.list_bytes},
               {"pvs_entries", r.pvs_entries},
               {"mean_pvs_size", r.mean_pvs},
               {"estimated_pixel_error", number_or_null(r.pixel_error)},
               {"pixel_error_bound", number_or_null(r.pixel_error_bound)},
               {"measured_pixel_error",
                r.measured ? json{{"pixels", r.measured->pixels},
                                  {"median_pixels", r.measured->median_pixels},
                                  {"share", r.measured->share},
                                  {"cameras", r.measured->cameras},
                                  {"cameras_with_wrong_pixels", r.measured->cameras_wrong},
                                  {"p99_pixels", r.measured->p99_pixels},
                                  {"worst_pixels", r.measured->worst_pixels},
                                  {"cameras_in_no_cell", r.measured->cameras_uncovered},
                                  {"placement", r.camera_rule},
                                  {"seed", c.cameras.seed},
                                  {"width", c.frame.width},
                                  {"height", c.frame.height},
                                  {"fov_degrees", c.frame.fov_degrees},
                                  {"resolution", c.frame.resolution}}
                           : json(nullptr)},
               {"measured_curve", measured_curve(r.measured_curve)},
               {"agvs",
                {{"samples", st.samples},
                 {"rays", st.rays},
                 {"stop_reason", st.stop_reason},
                 {"cells", r.agvs_cells},
                 {"distributions", agvs_distributions(st)}}},
               {"construction", {{"valid_segments", r.sampling.valid_segments}, {"samples", r.sampling.samples}}},
               {"timings",
                {{"hierarchy_seconds", r.hierarchy_seconds},
                 {"agvs_seconds", st.seconds},
                 {"total_seconds", r.seconds}}}});
}

std::string query_json(const PvsFile& f, const Vec3& p, int32_t cell) {
  const std::vector<uint32_t> pvs = f.pvs.cell_pvs(static_cast<uint32_t>(cell));
  json objects = json::array();
  for (uint32_t o : pvs) objects.push_back({{"id", o}, {"name", f.object_names.empty() ? "" : f.object_names[o]}});
  return json{{"point", {p.x, p.y, p.z}},
              {"cell", cell},
              {"cells", f.pvs.cell_count},
              {"merge_node", f.cell_mht_node[cell]},
              {"pvs", objects}}
             .dump(2) +
         "\n";
}

std::string report_json(const MeasureResult& r) {
  const MeasureConfig& c = r.config;
  json worst = json::array();
  for (const WrongObject& w : r.worst)
    worst.push_back({{"object", w.object}, {"name", w.name}, {"pixels", w.pixels}, {"cameras", w.cameras}, {"cause", w.cause}});
  json report = {
      {"command", "measure"},
      {"scene", c.scene.path},
      {"measured", r.measured},
      {"pvs_file", c.pvs_path.empty() ? json(nullptr) : json(c.pvs_path)},
      {"cells", r.cells},
      {"objects", r.objects},
      {"pvs_entries", r.pvs_entries},
      {"storage_bytes", r.storage_bytes},
      {"pvs_bytes", r.pvs_bytes},
      {"cameras", {{"count", r.error.cameras},
                   {"placement", r.camera_rule},
                   {"points_drawn", r.camera_points_drawn},
                   {"seed", c.cameras.seed},
                   {"width", c.frame.width},
                   {"height", c.frame.height},
                   {"fov_degrees", c.frame.fov_degrees},
                   {"primary_rays_per_second",
                    {{"coherent", r.ray_rates.coherent_per_second},
                     {"incoherent", r.ray_rates.incoherent_per_second},
                     {"rays_timed", r.ray_rates.rays}}}}},
      {"frame", {{"cost", r.frame_cost},
                 {"median_cost", r.median_frame_cost},
                 {"triangles", r.frame_triangles},
                 {"objects", r.frame_objects},
                 {"cost_model", {{"a", c.model.a}, {"b", c.model.b}}}}},
      {"pixel_error", {{"pixels", r.error.pixels},
                       {"median_pixels", r.error.median_pixels},
                       {"share", r.error.share},
                       {"resolution", c.frame.resolution},
                       {"cameras_with_wrong_pixels", r.error.cameras_wrong},
                       {"frames_with_wrong_pixels_share",
                        r.error.wrong_frame_share()},
                       {"p99_pixels", r.error.p99_pixels},
                       {"worst_pixels", r.error.worst_pixels},
                       {"cameras_in_no_cell", r.error.cameras_uncovered},
                       {"by_cause", r.wrong_by_cause},
                       {"worst_objects", worst}}},
      {"seconds", r.seconds}};
  if (r.leaf_surface_bytes) report["leaf_surface_bytes"] = r.leaf_surface_bytes;
  return text(report);
}

template <class Result>
void write_report(const std::string& path, const Result& result) {
  write_text_file(path, report_json(result));
}
template void write_report(const std::string&, const SceneInfo&);
template void write_report(const std::string&, const SampleResult&);
template void write_report(const std::string&, const BuildResult&);
template void write_report(const std::string&, const ExtractResult&);
template void write_report(const std::string&, const CompressResult&);
template void write_report(const std::string&, const PvsResult&);
template void write_report(const std::string&, const CompareRunResult&);
template void write_report(const std::string&, const BakeResult&);
template void write_report(const std::string&, const MeasureResult&);

}  // namespace viewcells::pipeline
