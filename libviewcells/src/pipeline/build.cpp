/// `viewcells build`: sample, subdivide (AV-S, paper 4.2), weigh the cells by the view space, merge
/// (4.3), write the .vcells.
#include "viewcells/pipeline/build.h"

#include <algorithm>
#include <optional>

#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"
#include "viewcells/validated/merge.h"
#include "viewcells/merge/merge.h"

namespace viewcells::pipeline {

void write_views(const Subdivision& s, const Scene* scene, const ViewsConfig& views, const Log& log,
                 const CellView* view) {
  if (!views.mesh.empty()) {
    write_cells_ply(views.mesh, s, view);
    log("viewcells: cells -> " + views.mesh + " (coloured by render cost)");
  }
  if (!views.slice_png.empty()) {
    const double z = std::isnan(views.slice_z) ? 0.5 * (s.view_box.lo.z + s.view_box.hi.z) : views.slice_z;
    write_slice_png(views.slice_png, s, z, views.slice_width, scene, view);
    log("viewcells: slice at z = " + fmt(z, 3) + " -> " + views.slice_png);
  }
}

namespace {

/// Subdivides the sampled view space (AV-S), weighting cells by the scene's view space (with
/// --play-space, its play space; `play_rule` says what that was).
Subdivision subdivide_sampled(SamplingRun& s, const CostModel& model, SubdivisionConfig& config,
                              std::string& play_rule, const Log& log) {
  std::string ga_reason;
  use_geometry_aligned(*s.loaded.scene, config, ga_reason);
  log("viewcells: subdividing to at most " + std::to_string(config.max_cells) + " cells; geometry-aligned candidates " +
      ga_reason);
  log("viewcells: pixel cost term " + model.describe_pixel_term());
  // With --play-space, the play space is the division's viewpoint density, and its volume in
  // each cell the cell's weight afterwards; otherwise the scene's view space weighs the cells.
  std::shared_ptr<const ViewSpace> space = s.loaded.view_space;
  if (config.play_space) {
    space = play_view_space(s.loaded);  // kept by the scene's view space: a bake's AGVS shares it
    space->set_viewpoints(config, s.result.segments.view_box);
    play_rule = space->viewpoint_rule();
    log("viewcells: viewpoint density: " + play_rule);
  }
  Subdivision sub = subdivide(*s.loaded.scene, s.result.segments, model, config);
  log("viewcells: " + std::to_string(sub.leaf_count()) + " cells in " + fmt(sub.stats.seconds, 2) +
      " s, render cost " + fmt(sub.initial_cost, 1) + " -> " + fmt(sub.cost(), 1) + " (" + sub.stats.stop_reason +
      ")");
  if (!config.density.enabled) {
    // p(i) over the view space: merging, extraction and the file use these weights.
    if (const std::function<void(Subdivision&)> weigh = space->weigher(sub.view_box)) {
      weigh(sub);
      log("viewcells: cells weighted by " + space->weight_rule());
    }
  }
  return sub;
}

/// The leaves' PVSs and, unless --no-merge, the merge history, into out.file.
void merge_leaves(const BuildConfig& config, const SamplingRun& s, const Subdivision& sub, BuildResult& out,
                  const Log& log) {
  SubdivisionFile& file = out.file;
  if (!config.merge) {
    file.leaf_pvs = leaf_pvs(sub, s.result.segments);
    return;
  }
  if (config.merge_agvs) {
    const AgvsConfig& a = *config.merge_agvs;
    log("viewcells: merging " + std::to_string(sub.leaf_count()) + " cells, on PVSs with two AGVS runs over them (" +
        (a.max_samples ? std::to_string(a.max_samples) + " samples" : "") +
        (a.max_samples && a.pixel_error > 0 ? " or " : "") +
        (a.pixel_error > 0 ? "pixel error " + fmt(a.pixel_error) : "") + " each: one to merge on, one to validate)");
  } else {
    log("viewcells: merging " + std::to_string(sub.leaf_count()) + " cells on the construction samples' PVSs");
  }
  MergeConfig mc;
  mc.show_progress = config.subdivision.show_progress;
  LeafMerge m = viewcells::merge_leaves(*s.loaded.scene, *s.loaded.caster, sub, s.result.segments,
                                        held_out_sampling(s.config, s.result.stats.samples), config.model,
                                        config.merge_agvs, mc);
  file.leaf_pvs = std::move(m.leaf_pvs);
  file.history = std::move(m.history);
  const MergeSummary& v = out.merge_summary = std::move(m.summary);
  if (v.validated)
    log("viewcells: " + describe_chain(v) + " (held-out mean log cost ratio to AV-S " + fmt(v.chosen.score, 4) +
        ", worst " + fmt(v.chosen.worst, 4) + ")");
  log("viewcells: leaf PVSs " + fmt(v.leaf_pvs_seconds, 2) + " s, neighbour graph " + fmt(v.neighbour_seconds, 2) +
      " s, merging " + fmt(v.merge_seconds, 2) + " s (" + std::to_string(file.history->stats.evaluations) +
      " pair costs, " + std::to_string(file.history->stats.stale) + " stale queue entries skipped)");
}

}  // namespace

namespace {

/// What the scene must be for the settings, checked before loading and sampling.
void check_for_scene(const BuildConfig& config) {
  if (config.subdivision.play_space && config.subdivision.density.enabled)
    throw Error("--play-space and --density-band are two viewpoint densities: give one");
  if (config.subdivision.play_space && !config.sampling.view_box.empty())
    throw Error("--play-space takes the map's whole view box (the play space says where viewpoints are): drop --view-box");
}

}  // namespace

BuildResult build(const BuildConfig& config, const Log& log) {
  config.model.validate();  // before loading and sampling, not after
  check_for_scene(config);
  return build(config, load_scene_for_rays(config.scene, log), log);
}

BuildResult build(const BuildConfig& config, LoadedScene loaded, const Log& log) {
  config.model.validate();
  check_for_scene(config);
  if (config.subdivision.play_space) play_view_space(loaded);  // before sampling: Error when there is none
  BuildResult out;
  out.model = config.model;
  out.merge = config.merge;
  out.sampling = sample_loaded(std::move(loaded), config.sampling, log);
  const SamplingRun& s = out.sampling;
  if (s.result.stats.valid_segments == 0)
    throw Error(config.scene.path, 0,
                "none of the " + std::to_string(s.result.stats.samples) + " samples saw an object (0 valid segments): "
                "the view space lies inside solids or sees no geometry; give a --view-box where a viewer can be, or "
                "--empty-space off when the objects' insides are not solid");
  const Box3& box = s.result.segments.view_box;
  if (!std::isnan(config.views.slice_z) && !(config.views.slice_z >= box.lo.z && config.views.slice_z <= box.hi.z))
    throw Error("--slice-z " + fmt(config.views.slice_z) + " lies outside the view space (z from " + fmt(box.lo.z) +
                " to " + fmt(box.hi.z) + ")");
  out.subdivision_config = config.subdivision;
  Subdivision sub = subdivide_sampled(out.sampling, config.model, out.subdivision_config, out.play_space, log);

  merge_leaves(config, s, sub, out, log);
  SubdivisionFile& file = out.file;
  file.cost_model = config.model;
  file.scene_fingerprint = s.loaded.scene->fingerprint();
  file.object_count = static_cast<uint32_t>(s.loaded.scene->object_count());
  for (const ObjectInfo& o : s.loaded.scene->objects) file.object_names.push_back(o.name);
  Stopwatch sw;
  write_views(sub, &*s.loaded.scene, config.views, log);
  out.export_seconds = sw.seconds();
  // The file keeps the tree, not the cells' polyhedra or per-leaf segment lists.
  file.subdivision = std::move(sub);
  file.subdivision.segments.clear();
  file.subdivision.cells.clear();
  sw.restart();
  if (!config.hierarchy_path.empty()) {
    write_subdivision(config.hierarchy_path, file);
    log("viewcells: hierarchy -> " + config.hierarchy_path);
  }
  out.write_seconds = sw.seconds();
  return out;
}

}  // namespace viewcells::pipeline
