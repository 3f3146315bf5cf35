/// `viewcells compare`: methods built from the same samples and scored on independent ones
/// (view-cell-construction paper, section 6).
#include "viewcells/studies/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/q3/level.h"

namespace viewcells::studies {

using namespace pipeline;

namespace {

bool has_point(const CostCurve& c, uint32_t n) { return std::binary_search(c.cells.begin(), c.cells.end(), n); }

const MethodResult* find_avm(const Comparison& cmp) {
  for (const MethodResult& m : cmp.methods)
    if (m.method == "av-m") return &m;
  return nullptr;
}

/// The methods and counts compare_methods is given, from the run's config.
CompareConfig compared_config(const CompareRunConfig& c, bool& with_q3) {
  CompareConfig config;
  if (!c.methods.empty()) config.methods = c.methods;
  // q3-clusters is not built but read from the map: compare_with_q3map2 adds it.
  const auto q3_entry = std::find(config.methods.begin(), config.methods.end(), "q3-clusters");
  with_q3 = q3_entry != config.methods.end();
  if (with_q3) config.methods.erase(q3_entry);
  const bool map = is_q3_map(c.scene.path);
  if (c.methods.empty() && map) {
    config.methods = {"av-m", "av-s", "kd-casm"};
    with_q3 = true;
  }
  if (with_q3 && !map) throw Error("q3-clusters needs a Quake 3 map (.bsp) as the scene");
  // On a map, by default three times as many cells as the map has clusters (0 until known).
  config.max_cells = c.max_cells ? c.max_cells : (with_q3 ? 0 : 1000);
  config.construction = c.construction;
  config.evaluation = c.construction;
  config.evaluation.target_segments = 0;
  config.evaluation.samples = c.evaluation_samples ? c.evaluation_samples : 4 * c.construction.samples;
  config.evaluation.seed = c.evaluation_seed ? c.evaluation_seed : c.construction.seed + 1'000'003;
  if (c.evaluation_sets < 1 || c.evaluation_sets > 16) throw Error("--eval-sets must be between 1 and 16");
  config.evaluation_sets = c.evaluation_sets;
  config.model = c.model;
  config.model.validate();
  config.subdivision = c.subdivision;
  config.subdivision.seed = c.construction.seed;
  config.subdivision.geometry_aligned = c.geometry_aligned_off ? GeometryAlignedMode::kOff : GeometryAlignedMode::kAuto;
  config.histogram_cells = c.histogram_cells;
  config.merge_agvs = c.merge_agvs;
  config.show_progress = c.construction.show_progress;
  check_methods(config.methods);  // before the output directory is made
  return config;
}

/// curves.csv: each method's evaluated cost at the report's counts and where any stopped; with
/// several evaluation sets, a column cost_K for each further set K (2, 3, ...); cost_half: set
/// 1's cost from the first half of its samples (Comparison::evaluation_half_samples).
void write_curves(const CompareRunResult& r, const std::string& path) {
  const Comparison& cmp = r.comparison();
  const MethodResult* avm = find_avm(cmp);
  const std::vector<uint32_t> counts = report_cell_counts(r.compared.max_cells);
  const uint32_t sets = r.compared.evaluation_sets;
  std::string csv = "method,cells,cost,ratio_to_av_m,constructed_cost";
  for (uint32_t k = 2; k <= sets; ++k) csv += ",cost_" + std::to_string(k);
  csv += ",cost_half\n";
  char line[256];
  for (const MethodResult& m : cmp.methods) {
    std::vector<uint32_t> at = counts;
    for (const MethodResult& other : cmp.methods) at.push_back(other.evaluated.cells.back());
    if (r.q3) {  // q3map2's cluster count and a quarter of it, where maps are compared
      at.push_back(r.q3->cluster_count);
      at.push_back(std::max<uint32_t>(1, r.q3->cluster_count / 4));
    }
    std::sort(at.begin(), at.end());
    at.erase(std::unique(at.begin(), at.end()), at.end());
    for (uint32_t n : at) {
      if (!has_point(m.evaluated, n)) continue;
      const double cost = m.evaluated.at(n);
      const std::string ratio = avm && has_point(avm->evaluated, n) ? fmt(cost / avm->evaluated.at(n), 6) : "";
      std::snprintf(line, sizeof line, "%s,%u,%.6g,%s,%.6g", m.method.c_str(), n, cost, ratio.c_str(),
                    m.constructed.at(n));
      csv += line;
      for (uint32_t k = 2; k <= sets; ++k) {
        const CostCurve* more = k - 2 < m.evaluated_more.size() ? &m.evaluated_more[k - 2] : nullptr;
        if (more && has_point(*more, n)) {
          std::snprintf(line, sizeof line, ",%.6g", more->at(n));
          csv += line;
        } else {
          csv += ",";
        }
      }
      if (has_point(m.evaluated_half, n)) {
        std::snprintf(line, sizeof line, ",%.6g", m.evaluated_half.at(n));
        csv += line;
      } else {
        csv += ",";
      }
      csv += "\n";
    }
  }
  if (r.q3) {
    // q3map2's clusters: one point, at the map's cluster count.
    const uint32_t n = r.q3->cluster_count;
    const std::string ratio =
        avm && has_point(avm->evaluated, n) ? fmt(r.q3->clusters.cost / avm->evaluated.at(n), 6) : "";
    std::snprintf(line, sizeof line, "q3-clusters,%u,%.6g,%s,", n, r.q3->clusters.cost, ratio.c_str());
    csv += line + std::string(sets, ',') + "\n";
  }
  write_text_file(path, csv);
}

void write_histograms(const Comparison& cmp, const std::string& path) {
  std::string hist = "method,cell,cost,volume\n";
  for (const MethodResult& m : cmp.methods)
    for (size_t i = 0; i < m.cells.size(); ++i) {
      char line[256];
      std::snprintf(line, sizeof line, "%s,%zu,%.6g,%.6g\n", m.method.c_str(), i, m.cells[i].cost, m.cells[i].volume);
      hist += line;
    }
  write_text_file(path, hist);
}

/// excluded.csv: every object seen from a cluster that q3map2 excludes it from; and the log.
void write_q3(const CompareRunResult& r, const std::string& dir, const Log& log) {
  const Q3Comparison& q = *r.q3;
  const Scene& scene = *r.loaded.scene;
  std::string csv = "cluster,object,name,cause,ax,ay,az,bx,by,bz\n";
  const SegmentSet& eval = q.ours.evaluation_segments;
  for (const Q3Excluded& e : q.excluded) {
    char line[512];
    std::snprintf(line, sizeof line, "%d,%u,\"%s\",%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", e.cluster, e.object,
                  scene.objects[e.object].name.c_str(), e.cause.c_str(), eval.ax[e.segment], eval.ay[e.segment],
                  eval.az[e.segment], eval.bx[e.segment], eval.by[e.segment], eval.bz[e.segment]);
    csv += line;
  }
  write_text_file(dir + "/excluded.csv", csv);
  const bool reached = std::isfinite(q.avm_cost_at_clusters);
  const double ours_bytes = static_cast<double>(q.ours_compressed_bytes);
  log("viewcells: q3map2: " + std::to_string(q.cluster_count) + " clusters, evaluated cost " +
      fmt(q.clusters.cost, 1) + "; AV-M at " + std::to_string(q.cluster_count) + " cells " +
      (reached ? fmt(q.avm_cost_at_clusters, 1) + " (" + fmt(q.avm_cost_at_clusters / q.clusters.cost, 3) + " x)"
               : std::string("not reached")) +
      "; AV-M matches q3map2 from " +
      (q.avm_cells_to_match ? std::to_string(q.avm_cells_to_match) + " cells" : std::string("no cell count built")));
  log("viewcells: q3map2: PVS size ratio ours / q3map2 " + fmt(q.mean_pvs_ratio, 3) + "; " +
      std::to_string(q.excluded.size()) + " objects seen from clusters q3map2 excludes them from (" + dir +
      "/excluded.csv); storage: q3map2 rows " + std::to_string(q.q3_row_bytes) + " B, ours " +
      std::to_string(q.ours_compressed_bytes) + " B (" + fmt(ours_bytes / std::max<double>(1, q.q3_row_bytes), 2) +
      " x)");
}

void log_methods(const CompareRunResult& r, const Log& log) {
  const Comparison& cmp = r.comparison();
  const MethodResult* avm = find_avm(cmp);
  for (const MethodResult& m : cmp.methods) {
    const uint32_t last = m.evaluated.cells.back();
    log("viewcells: " + m.method + ": " + std::to_string(m.leaves) + " cells in " + fmt(m.build_seconds, 2) +
        " s; evaluated cost " + fmt(m.evaluated.at(last), 1) + " at " + std::to_string(last) + " cells" +
        (avm && has_point(avm->evaluated, last)
             ? " (" + fmt(m.evaluated.at(last) / avm->evaluated.at(last), 3) + " x AV-M)"
             : ""));
  }
  // Sampled PVSs only miss objects: a cost still rising with the evaluation samples is not yet
  // the cost a viewer pays, and a method that rises more than another is flattered by it.
  if (!cmp.evaluation_half_samples) return;
  std::string rises;
  for (const MethodResult& m : cmp.methods) {
    const HalfSampleRise rise = half_sample_rise(m);
    if (!rise.cells) continue;
    rises += (rises.empty() ? "" : ", ") + m.method + " +" + fmt(100 * rise.rise, 1) + "% at " +
             std::to_string(rise.cells) + " cells";
  }
  if (!rises.empty())
    log("viewcells: evaluator: the evaluation samples after the first " + std::to_string(cmp.evaluation_half_samples) +
        " of " + std::to_string(r.compared.evaluation.samples) + " raised the costs from 16 cells on by at most: " +
        rises + " (0 would be converged; raise --eval-samples where a method rises more than the others)");
}

}  // namespace

CompareRunResult compare(const CompareRunConfig& c, const Log& log) {
  CompareRunResult out;
  out.config = c;
  out.threads = worker_threads();
  bool with_q3 = false;
  CompareConfig& config = out.compared;
  config = compared_config(c, with_q3);
  std::filesystem::create_directories(c.output_dir);
  out.loaded = load_scene_for_rays(c.scene, log);
  std::string method_list;
  for (const std::string& m : config.methods) method_list += (method_list.empty() ? "" : ",") + m;
  if (with_q3) {
    method_list += ",q3-clusters";
    if (!q3_map_of(out.loaded.level.get()))
      throw Error(c.scene.path, 0, "q3-clusters needs the map read as a Quake 3 level (register_q3_map_format())");
    if (!q3_map_of(out.loaded.level.get())->has_visibility())
      throw Error(c.scene.path, 0, "the map has no visibility data: there are no q3map2 clusters to compare with");
    if (config.max_cells == 0) config.max_cells = 3 * static_cast<uint32_t>(q3_map_of(out.loaded.level.get())->cluster_count);
  }
  // The scene's view space (on a map its non-solid space), for both samplers and the cells' weights.
  out.loaded.view_space->restrict(config.construction);
  if (config.construction.view_space) {
    config.evaluation.view_space = config.construction.view_space;
    config.evaluation.view_box = config.construction.view_box;
  }
  if (!with_q3) config.prepare = out.loaded.view_space->weigher(config.construction.view_box);
  log("viewcells: comparing " + method_list + " up to " + std::to_string(config.max_cells) + " cells; " +
      std::to_string(config.construction.samples) + " construction samples (seed " +
      std::to_string(config.construction.seed) + "), " + std::to_string(config.evaluation.samples) +
      " evaluation samples (seed " + std::to_string(config.evaluation.seed) + "); view space " +
      out.loaded.view_space->describe());
  if (with_q3) out.q3 = compare_with_q3map2(*out.loaded.scene, *q3_map_of(out.loaded.level.get()), *out.loaded.caster, config);
  else out.plain = compare_methods(*out.loaded.scene, *out.loaded.caster, config);
  write_curves(out, c.output_dir + "/curves.csv");
  write_histograms(out.comparison(), c.output_dir + "/histogram.csv");
  if (out.q3) write_q3(out, c.output_dir, log);
  write_text_file(c.output_dir + "/summary.json", report_json(out));
  log_methods(out, log);
  log("viewcells: curves -> " + c.output_dir + "/curves.csv, histograms -> " + c.output_dir +
      "/histogram.csv; plots: bash scripts/plot-compare.sh " + c.output_dir);
  return out;
}

}  // namespace viewcells::studies
