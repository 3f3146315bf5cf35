// The pipeline's JSON reports (pipeline/report.h): the only place they are assembled. Here the
// reports of info, sample, build, extract and compress, and query's answer; report_runs.cpp
// has those of pvs, compare, bake and measure, and report_parts.cpp what they share.
#include "viewcells/pipeline/report.h"
#include "report_parts.h"

#include <nlohmann/json.hpp>

#include <cmath>

#include "viewcells/core/ranks.h"
#include "viewcells/core/format.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/binary_file.h"

namespace viewcells::pipeline {

using namespace report_detail;  // the shared parts (report_parts.h)

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
  if (info.level) j[info.level->info_key()] = json::parse(info.level->info_json());
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
template void write_report(const std::string&, const BakeResult&);
template void write_report(const std::string&, const MeasureResult&);

}  // namespace viewcells::pipeline
