// build, export: view cells from the scene's visibility, and pictures of them.
#include <memory>

#include "options.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pipeline/build.h"
#include "viewcells/pipeline/report.h"

namespace viewcells::cli {

namespace {

struct BuildArgs {
  SamplingOptions sampling;
  CellOptions cells;
  bool no_merge = false;
  MergeOptions merge;
  std::string output, report;
  pipeline::ViewsConfig views;
};

int run_build(const BuildArgs& a, const Common& c) {
  check_files({a.sampling.scene}, {a.output, a.report, a.views.mesh, a.views.slice_png});
  ThreadLimit threads(c.threads);
  pipeline::BuildConfig config;
  config.model = a.cells.model();  // before the sampling, not after
  config.subdivision = a.cells.subdivision(c.quiet, a.sampling);
  config.scene = a.sampling.source();
  config.sampling = a.sampling.sampler(c.quiet);
  config.merge = !a.no_merge;
  if (!a.no_merge) config.merge_agvs = a.merge.agvs(c.quiet, a.sampling.seed, config.sampling.samples);
  config.hierarchy_path = a.output;
  config.views = a.views;
  const pipeline::BuildResult result = pipeline::build(config, c.logger());
  write_report_to(a.report, result, c);
  return 0;
}

struct ExportArgs {
  std::string input, scene, objects = "auto";
  pipeline::ViewsConfig views;
};

int run_export(const ExportArgs& e, const Common& c) {
  check_files({e.input, e.scene}, {e.views.mesh, e.views.slice_png});
  if (!e.views.any()) throw Error("nothing to export: give --mesh and/or --slice-png");
  SubdivisionFile file = read_subdivision(e.input);
  rebuild_cells(file.subdivision);
  c.log("viewcells: " + e.input + ": " + std::to_string(file.subdivision.leaf_count()) + " cells, render cost " +
        fmt(file.subdivision.cost(), 1));
  std::unique_ptr<Scene> scene;
  if (!e.scene.empty()) {
    scene = std::make_unique<Scene>(
        pipeline::load_matching_scene(e.scene, parse_grouping(e.objects), file.scene_fingerprint, e.input));
  }
  pipeline::write_views(file.subdivision, scene.get(), e.views, c.logger());
  return 0;
}

}  // namespace

void add_build_commands(CLI::App& app, const Common& common, Commands& commands) {
  auto b = std::make_shared<BuildArgs>();
  auto* bc = app.add_subcommand("build", "Sample visibility and subdivide the view space into cells (AV-S, section 4.2)");
  add_sampling_options(bc, b->sampling);
  add_floor_options(bc, b->sampling.floors);
  add_cell_options(bc, b->cells, "Stop at this many cells");
  bc->add_flag("--no-merge", b->no_merge, "Keep the AV-S cells: no merge history (extract and compress need one)");
  add_merge_options(bc, b->merge);
  bc->add_option("-o,--output", b->output, "Hierarchy file to write (.vcells)");
  bc->add_option("--report", b->report, "JSON report: settings, effects and why, costs, candidates, timings");
  add_view_options(bc, b->views, "Also write the cells as a PLY coloured by render cost",
                   "Also write a PNG of a horizontal slice through the cells");
  commands.push_back({bc, [b, &common] { return run_build(*b, common); }});

  auto e = std::make_shared<ExportArgs>();
  auto* ex = app.add_subcommand("export", "Look at a built hierarchy: cells as PLY, or a slice as PNG");
  ex->add_option("cells", e->input, "Hierarchy file (.vcells)")->required();
  add_view_options(ex, e->views, "PLY of the cells, coloured by render cost", "PNG of a horizontal slice");
  ex->add_option("--scene", e->scene,
                 "Draw this scene's cross-section into the slice (the scene the cells were built from)");
  ex->add_option("--objects", e->objects, "With --scene: the object grouping the cells were built with")
      ->capture_default_str();
  commands.push_back({ex, [e, &common] { return run_export(*e, common); }});
}

}  // namespace viewcells::cli
