#pragma once
/// `viewcells build`: sample, subdivide the view space (AV-S), weight the cells by the map's
/// view space on a Quake 3 map, compute the leaves' PVSs from the samples, merge them into a
/// history, write the hierarchy (.vcells) and the views asked for.
#include <cmath>
#include <optional>
#include <string>

#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/validated/merge.h"
#include "viewcells/vis/cell_views.h"
#include "viewcells/pipeline/sampling.h"

namespace viewcells::pipeline {

/// Pictures of cells: a PLY coloured by render cost and a PNG of a horizontal slice.
struct ViewsConfig {
  std::string mesh;       ///< empty: none
  std::string slice_png;  ///< empty: none
  double slice_z = NAN;   ///< NaN: the middle of the view space
  int slice_width = 1024;
  bool any() const { return !mesh.empty() || !slice_png.empty(); }
};

/// Writes the views of `s` (its cells must be built); `view` colours merged view cells.
void write_views(const Subdivision& s, const Scene* scene, const ViewsConfig& views, const Log& log,
                 const CellView* view = nullptr);

struct BuildConfig {
  SceneSource scene;
  SamplerConfig sampling;
  CostModel model;
  SubdivisionConfig subdivision;
  bool merge = true;
  /// Merging validated by AGVS runs over the leaves with this config (validated/merge.h);
  /// unset: greedy merging of the leaves on the construction samples' PVSs.
  std::optional<AgvsConfig> merge_agvs;
  std::string hierarchy_path;  ///< .vcells to write; empty: none
  ViewsConfig views;
};

struct BuildResult {
  SamplingRun sampling;
  CostModel model;
  SubdivisionConfig subdivision_config;  ///< as used (geometry-aligned decided)
  bool merge = true;
  MergeSummary merge_summary;  ///< what merging chose, and its seconds (with a history)
  std::string play_space;      ///< with SubdivisionConfig::play_space: the play space, in words
  /// The hierarchy: the subdivision (its cells and per-leaf segments dropped once written),
  /// the leaves' PVSs and, when merged, the merge history.
  SubdivisionFile file;
  double write_seconds = 0, export_seconds = 0;
};

BuildResult build(const BuildConfig& config, const Log& log);
/// The same for a scene already loaded (config.scene says only what it is; it moves into the
/// result's sampling run).
BuildResult build(const BuildConfig& config, LoadedScene loaded, const Log& log);

}  // namespace viewcells::pipeline
