// The parts the pipeline's JSON reports share (report_parts.h).
#include "report_parts.h"

#include <nlohmann/json.hpp>

#include <cmath>

#include "viewcells/core/ranks.h"
#include "viewcells/core/format.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/binary_file.h"

namespace viewcells::pipeline::report_detail {

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
    if (ranks::size() > 1) {
      const ranks::Traffic& t = ranks::traffic();
      j["cluster"] = {{"ranks", ranks::size()},
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
          {"restricted_view_space", effect(static_cast<bool>(s.config.view_space), s.loaded.view_space->describe())}};
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
                                            : (!s.view_box_given ? s.loaded.view_space->box_rule()
                                                                 : std::string("user (--view-box)"))},
                        {"view_space", s.loaded.view_space->describe()},
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
      !r.play_space.empty() ? effect(true, "the play space (--play-space, bake's default where the scene has one): p(i) is the "
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
                   {"cameras", p.measured.cameras},
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

json agvs_view_space(bool restricted, bool play) {
  return effect(restricted, play         ? "the play space (--play-space, bake's default where the scene has one): "
                                           "AGVS's points are drawn where a player's eye can be (settings.view_space "
                                           "says how it was found)"
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

}  // namespace viewcells::pipeline::report_detail
