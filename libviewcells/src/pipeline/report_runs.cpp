// The JSON reports of the runs that sample PVSs and measure them (pipeline/report.h): pvs,
// compare, bake and measure.
#include "report_parts.h"

#include <nlohmann/json.hpp>

#include <cmath>

#include "viewcells/core/ranks.h"
#include "viewcells/core/format.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/binary_file.h"

namespace viewcells::pipeline {

using namespace report_detail;  // the shared parts (report_parts.h)

namespace {
/// Each rank's phases: with its waiting in collectives, whether more ranks would help.
json rank_phases_json(const std::vector<RankPhases>& ranks) {
  json a = json::array();
  for (size_t i = 0; i < ranks.size(); ++i) {
    const RankPhases& p = ranks[i];
    a.push_back({{"rank", i},
                 {"draw_seconds", p.draw_seconds},
                 {"mutation_seconds", p.mutation_seconds},
                 {"cast_seconds", p.cast_seconds},
                 {"apply_seconds", p.apply_seconds},
                 {"exchange_seconds", p.exchange_seconds}});
  }
  return a;
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
                 {"pierced_cells", st.pierced_cells},
                 {"per_rank", rank_phases_json(r.rank_phases)}}},
               {"distributions", agvs_distributions(st)},
               {"curve", agvs_curve(st, c.references.size())}});
}

/// The three answers per (view cell, object) pair (BakeResult::HiddenClasses).
json hidden_classes(const BakeResult::HiddenClasses& h, const BakeConfig& c) {
  if (!h.proved)
    return {{"proved", false},
            {"reason", h.method.empty() ? std::string("not asked for (--prove-hidden, --conservative)") : h.method}};
  return {{"proved", true},
          {"method", h.method},
          {"warnings", h.warnings},
          {"conservative", c.conservative},
          {"pairs", {{"proven_visible", h.visible}, {"proven_hidden", h.hidden}, {"undecided", h.undecided}}},
          {"seen_but_proven_hidden", h.conflicts},
          {"cost_per_frame", {{"proven_visible", h.cost_visible}, {"with_undecided", h.cost_conservative},
                              {"weighed_by", h.weights}}},
          {"floods", h.floods},
          {"portal_steps", h.steps},
          {"floods_over_budget", h.overflows},
          {"cells_unproven_by_time", h.cells_unproven},
          {"aimed_rays", {{"per_pair", c.aimed_rays}, {"pairs", h.aimed_pairs}, {"rays", h.aimed_rays},
                          {"found_visible", h.aimed_found}, {"seconds", h.aimed_seconds}}},
          {"max_steps", c.hidden_max_steps},
          {"seconds", h.seconds}};
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
                 {"view_space", r.view_space_choice},
                 {"decided", r.decided},
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
                  effect(c.near.rays_per_object > 0 && r.near_skipped.empty(),
                         !r.near_skipped.empty() ? "skipped: no viewpoints (" + r.near_skipped + ")"
                         : c.near.rays_per_object > 0
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
                                  {"cameras_asked", r.measured->cameras_asked},
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
               {"hidden", hidden_classes(r.hidden, c)},
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

std::string report_json(const MeasureResult& r) {
  const MeasureConfig& c = r.config;
  json worst = json::array();
  for (const WrongObject& w : r.worst)
    worst.push_back({{"object", w.object}, {"name", w.name}, {"pixels", w.pixels}, {"cameras", w.cameras}, {"cause", w.cause}});
  json frames = json::array();
  for (const WrongFrame& f : r.worst_frames) {
    json objects = json::array();
    for (const auto& [o, px] : f.objects) objects.push_back({{"object", o}, {"pixels", px}});
    frames.push_back({{"camera", f.camera}, {"cell", f.cell}, {"eye", {f.eye.x, f.eye.y, f.eye.z}},
                      {"forward", {f.forward.x, f.forward.y, f.forward.z}}, {"up", {f.up.x, f.up.y, f.up.z}},
                      {"pixels", f.pixels}, {"objects", objects}});
  }
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
                       {"worst_objects", worst},
                       {"worst_frames", frames}}},
      {"seconds", r.seconds}};
  if (r.leaf_surface_bytes) report["leaf_surface_bytes"] = r.leaf_surface_bytes;
  return text(report);
}

}  // namespace viewcells::pipeline
