#pragma once
/// `viewcells compare`: view cells by several methods from the same construction samples,
/// scored on independent evaluation samples (paper, section 6); on a Quake 3 map also
/// against the clusters q3map2 compiled into it. Writes curves.csv, histogram.csv,
/// excluded.csv (maps) and summary.json into a directory.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/studies/methods.h"
#include "viewcells/pipeline/sampling.h"
#include "viewcells/studies/q3map2.h"

namespace viewcells::studies {

using pipeline::LoadedScene;
using pipeline::Log;
using pipeline::SceneSource;

struct CompareRunConfig {
  SceneSource scene;
  /// Methods as in eval/compare.h, plus "q3-clusters" (a map's own clusters). Empty: all of
  /// eval's methods, or on a map av-m, av-s, kd-casm and q3-clusters.
  std::vector<std::string> methods;
  uint32_t max_cells = 0;  ///< 0: 1000, or on a map three times its clusters
  SamplerConfig construction;
  uint64_t evaluation_samples = 0;  ///< 0: four times the construction samples
  uint64_t evaluation_seed = 0;     ///< 0: the construction seed + 1000003
  uint32_t evaluation_sets = 1;     ///< independent evaluation sets (eval/compare.h)
  uint32_t histogram_cells = 0;
  CostModel model;
  SubdivisionConfig subdivision;
  bool geometry_aligned_off = false;
  std::optional<AgvsConfig> merge_agvs;  ///< AV-M's leaf PVSs by AGVS too (eval/compare.h)
  std::string output_dir;
};

struct CompareRunResult {
  CompareRunConfig config;
  CompareConfig compared;  ///< as run (methods, counts, samplers)
  LoadedScene loaded;
  Comparison plain;
  std::optional<Q3Comparison> q3;
  int threads = 1;
  const Comparison& comparison() const { return q3 ? q3->ours : plain; }
};

/// Runs the comparison and writes the directory's files (summary.json: report_json).
CompareRunResult compare(const CompareRunConfig& config, const Log& log);

/// The run's summary.json (indented, with a final newline).
std::string report_json(const CompareRunResult& result);

}  // namespace viewcells::studies
