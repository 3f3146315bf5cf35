// pvs, bake: potentially visible sets by adaptive global visibility sampling.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <tuple>

#include "commands.h"
#include "options.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/pvs.h"
#include "viewcells/pipeline/report.h"

namespace viewcells::cli {

namespace {

/// When AGVS stops, and how it samples: the options bind to `bound`'s fields (its defaults are
/// the command line's); the method's name is parsed when the command runs.
struct AgvsOptions {
  AgvsConfig bound;
  std::string method = "agvs";

  AgvsConfig config(const Common& c) const {
    AgvsConfig a = bound;
    a.method = parse_agvs_method(method);
    a.show_progress = !c.quiet;
    return a;
  }
};

/// pvs's AGVS options: bake's (its table's help and checks), --agvs-time and --agvs-samples
/// named --time and --samples, and --method.
void add_agvs_options(CLI::App* cmd, AgvsOptions& a) {
  auto shared = [cmd](const std::string& flag, const std::string& table_flag, auto& field) {
    const pipeline::BakeOption& o = *pipeline::find_bake_option(table_flag);
    CLI::Option* opt = cmd->add_option(flag, field, o.help)->check(table_check(o));
    if (o.show_default) opt->capture_default_str();
  };
  shared("--pixel-error", "--pixel-error", a.bound.pixel_error);
  shared("--time", "--agvs-time", a.bound.max_seconds);
  shared("--samples", "--agvs-samples", a.bound.max_samples);
  cmd->add_option("--method", a.method, "agvs (adaptive mixture), sgvs (view space-direction only) or ref (per cell)")
      ->capture_default_str();
  shared("--batch", "--batch", a.bound.batch_size);
  shared("--mutation-lanes", "--mutation-lanes", a.bound.mutation_lanes);
  shared("--min-share", "--min-share", a.bound.min_share);
}

/// `pvs`'s options: bound to the fields of `config` (what the library runs), but for the few
/// that are parsed or shared when the command runs.
struct PvsArgs {
  pipeline::PvsConfig config;
  std::string report, objects = "auto";
  AgvsOptions agvs;
  bool fast = false;
};

int run_pvs(const PvsArgs& args, const Common& c) {
  const pipeline::PvsConfig& a = args.config;
  {
    // --save may be the --resume state (continue and keep it up to date); nothing else may meet.
    std::error_code ec;
    const bool save_is_resume = !a.save.empty() && !a.resume.empty() &&
                                (a.save == a.resume || std::filesystem::equivalent(a.save, a.resume, ec));
    std::vector<std::string> inputs = {a.hierarchy_path, a.scene_path, a.edited_from, save_is_resume ? "" : a.resume};
    inputs.insert(inputs.end(), a.references.begin(), a.references.end());
    check_files(inputs, {a.output, args.report, a.save});
  }
  ThreadLimit threads(c.threads);
  pipeline::PvsConfig config = a;
  config.grouping = parse_grouping(args.objects);
  config.robust = !args.fast;
  config.agvs = args.agvs.config(c);
  const pipeline::PvsResult result = pipeline::compute_pvs(config, c.logger());
  write_report_to(args.report, result, c);
  return 0;
}

void add_pvs_command(CLI::App& app, const Common& common, Commands& commands) {
  auto a = std::make_shared<PvsArgs>();
  auto* pv = app.add_subcommand("pvs",
                                "Compute the view cells' PVSs by adaptive global visibility sampling (AGVS) and write "
                                "them, compressed, as a .pvs file");
  pv->add_option("cells", a->config.hierarchy_path, "Hierarchy file (.vcells, built with merging)")->required();
  pv->add_option("--scene", a->config.scene_path, "The scene the hierarchy was built from")->required();
  pv->add_option("--objects", a->objects, "Object grouping used when building")->capture_default_str();
  pv->add_option("--cells", a->config.cells, "View cells cut from the merge history (default: every elementary cell)")
      ->check(whole(1, kMaxCells));
  add_agvs_options(pv, a->agvs);
  pv->add_option("--seed", a->agvs.bound.seed, "Random seed")
      ->capture_default_str()
      ->check(whole(0, UINT64_MAX));
  pv->add_flag("--fast", a->fast, "Embree without robust mode");
  pv->add_option("--measure-cameras", a->config.measure_cameras,
                 "Also measure the pixel error: render this many cameras by ray casting and count the pixels whose "
                 "object is missing from the PVS (cameras at random points of the view box looking anywhere; on a "
                 "Quake 3 map, player eyes above floors reachable from the spawn points, as `measure` places them)")
      ->check(whole(1, 1'000'000));
  auto* save = pv->add_option("--save", a->config.save,
                               "Write the solver's state here at the end, to continue later with --resume");
  pv->add_option("--save-every", a->config.save_every,
                 "With --save: also write the state every this many seconds (a checkpoint a cut-off run resumes "
                 "from, with any number of ranks)")
      ->needs(save)
      ->check(positive());
  pv->add_option("--resume", a->config.resume,
                 "Continue from a state written by --save (same scene, cells, method, seed and batch); --samples "
                 "and --time count from the start of the computation, the saved part included");
  pv->add_flag("--filter", a->config.filter_object_space,
               "Write PVSs extended by the object space visibility filter: objects near the PVS's objects, within "
               "a distance that shrinks as the sampling gets denser (sampling itself goes on unfiltered)");
  pv->add_option("--filter-k", a->config.filter.k, "The filter's factor k: larger is more conservative")
      ->capture_default_str();
  pv->add_option("--filter-neighbours", a->config.filter.view_neighbours,
                 "View space filter: merge each cell's PVS with those of this many neighbouring cells with the most "
                 "similar PVSs");
  pv->add_option("--edited-from", a->config.edited_from,
                 "Dynamic edit: --scene is an edited version of this scene (the one the hierarchy and the --resume "
                 "state were computed on). Objects are matched by name and geometry; deleted ones leave the PVSs, "
                 "and what inserted ones may hide is removed before sampling resumes");
  pv->add_option("--reference", a->config.references,
                 "A .pvs of the same cells (another method's result; up to 2): the report's curve counts the "
                 "entries found so far that it has too")
      ->expected(1, AgvsPoint::kReferences)
      ->check(CLI::ExistingFile);
  pv->add_option("--measure-at", a->config.measure_at,
                 "With --measure-cameras: also measure the PVSs after these sample counts (increasing), with the same "
                 "cameras, for a convergence curve by measured error (the report's measured_curve; the solver's "
                 "clock stops while measuring)")
      ->check(whole(1, kMaxSamples));
  pv->add_option("--measured-error", a->config.measured_error,
                 "With --measure-cameras: stop when the measured pixel error (the cameras' mean wrong pixels of "
                 "1024x1024) is at most this. The PVSs are measured after one batch and at every doubling of the "
                 "samples (each measurement in the report's measured_curve), so a run may sample up to twice what "
                 "it needed; other limits still apply")
      ->check(non_negative());
  pv->add_option("--measure-size", a->config.measure_size, "Width and height of the measuring cameras, in pixels")
      ->capture_default_str()
      ->check(whole(1, 2048));
  pv->add_option("-o,--output", a->config.output, "The .pvs file to write")->required();
  pv->add_option("--report", a->report, "JSON report: samples, rays, mean PVS size, estimated pixel error, curve");
  commands.push_back({pv, [a, &common] { return run_pvs(*a, common); }});
}

/// `bake`'s options: the table's (pipeline/options.h), the scene, -o and --report.
struct BakeArgs {
  pipeline::BakeOptions options;
  std::string report;
};

int run_bake(const BakeArgs& a, const Common& c) {
  check_files({a.options.sampling.scene}, {a.options.bound.output, a.report}, {a.options.bound.work_dir});
  ThreadLimit threads(c.threads);
  const pipeline::BakeConfig config = a.options.config(c.quiet);
  const pipeline::BakeResult result = pipeline::bake(config, c.logger());
  write_report_to(a.report, result, c);
  return 0;
}

/// Adds `bake`: its options are the table's, which Python's keywords and vc_bake's words set too.
std::shared_ptr<BakeArgs> add_bake_command(CLI::App& app, const Common& common, Commands& commands) {
  auto a = std::make_shared<BakeArgs>();
  auto* bk = app.add_subcommand(
      "bake",
      "The whole chain in one command: sample, subdivide and merge, cut view cells under the budget, compute "
      "their PVSs by AGVS to the pixel error asked for, compress and write a .pvs file for the engine");
  bk->add_option("scene", a->options.sampling.scene, "Scene file (.obj, .ply, .off, .stl, or a Quake 3 .bsp)")
      ->required();
  add_bake_options(bk, a->options);
  bk->add_option("-o,--output", a->options.bound.output, "The .pvs file to write")->required();
  bk->add_option("--report", a->report, "JSON report: budget, cells, file bytes, pixel error, samples, timings");
  bk->footer("Without --pixel-error, --measured-error, --time, --agvs-time or --agvs-samples, AGVS runs to an "
             "estimated pixel error of 10 (of 1024x1024).");
  commands.push_back({bk, [a, &common] { return run_bake(*a, common); }});
  return a;
}

}  // namespace

/// `measure`'s options, bound to the fields of `config` (the command line's default is 1,000
/// cameras); the grouping, the placement and robust mode are parsed when it runs.
struct MeasureArgs {
  pipeline::MeasureConfig config = [] {
    pipeline::MeasureConfig m;
    m.cameras.count = 1000;
    return m;
  }();
  std::string objects = "auto", cameras = "auto", report;
  bool fast = false;
  FloorOptions floors;
};

int run_measure(const MeasureArgs& a, const Common& c) {
  check_files({a.config.scene.path, a.config.pvs_path, a.config.cameras_in}, {a.report, a.config.cameras_out});
  ThreadLimit threads(c.threads);
  pipeline::MeasureConfig config = a.config;
  config.scene.grouping = parse_grouping(a.objects);
  config.scene.robust = !a.fast;
  config.scene.floors = a.floors.floors();
  config.cameras.placement = pipeline::parse_camera_placement(a.cameras);
  config.model.validate();
  const pipeline::MeasureResult result = pipeline::measure(config, c.logger());
  write_report_to(a.report, result, c);
  if (a.report.empty()) std::cout << pipeline::report_json(result);
  return 0;
}

void add_measure_command(CLI::App& app, const Common& common, Commands& commands) {
  auto a = std::make_shared<MeasureArgs>();
  auto* ms = app.add_subcommand(
      "measure",
      "Measure what a shipped PVS gives a viewer: render cameras by ray casting, and per frame count what the engine "
      "draws (the PVS of the camera's view cell: render cost, triangles, objects) and the pixels it gets wrong "
      "(objects shown but missing from that PVS). Without a .pvs, a Quake 3 map's own PVS (q3map2's vis rows) is "
      "measured, so both sides of a comparison meet the same cameras");
  ms->add_option("scene", a->config.scene.path, "The scene (a Quake 3 map .bsp, or any scene file)")->required();
  ms->add_option("pvs", a->config.pvs_path, "A .pvs file made for the scene (from bake, pvs or compress)");
  ms->add_option("--objects", a->objects, "Object grouping used when the .pvs file was made")->capture_default_str();
  ms->add_option("--cameras", a->cameras,
                 "Where cameras stand: play (a Quake 3 map: player eyes 50 units above walkable floors reachable "
                 "from the spawn points; other scenes: eyes above the floors of the play space found from the "
                 "geometry, see the play-space options; any yaw, pitch within --max-pitch), view-box (uniform random "
                 "points of the view space, looking anywhere) or auto (play on a map, view-box elsewhere)")
      ->capture_default_str();
  ms->add_option("--count", a->config.cameras.count, "Number of cameras")->capture_default_str()->check(whole(1, 10'000'000));
  ms->add_option("--width", a->config.frame.width,
                 "Frame width in pixels (what players see; wrong pixels are reported per 1024x1024 frame whatever "
                 "the size). Cameras x width x height may not exceed 2^32 rays")
      ->capture_default_str()
      ->check(whole(1, 2048));
  ms->add_option("--height", a->config.frame.height, "Frame height in pixels")->capture_default_str()->check(whole(1, 2048));
  ms->add_option("--fov", a->config.frame.fov_degrees, "Horizontal field of view in degrees")->capture_default_str()->check(in_range(1.0, 179.0));
  ms->add_option("--max-pitch", a->config.cameras.play.max_pitch_degrees, "Play cameras: largest pitch up or down, in degrees")
      ->capture_default_str()
      ->check(in_range(0.0, 89.0));
  ms->add_option("--seed", a->config.cameras.seed, "Random seed of the cameras")
      ->capture_default_str()
      ->check(whole(0, UINT64_MAX));
  ms->add_option("--cost-a", a->config.model.a, "Render cost model: r = max(a, b * triangles)")->capture_default_str();
  ms->add_option("--cost-b", a->config.model.b, "Render cost model: cost per triangle")->capture_default_str();
  ms->add_flag("--fast", a->fast, "Embree without robust mode");
  ms->add_option("--cameras-out", a->config.cameras_out,
                 "Write the cameras measured to this JSON file (eyes in metres, forward and up), to measure "
                 "another version of the level with the same frames");
  ms->add_option("--cameras-from", a->config.cameras_in,
                 "Measure with the cameras of this file (from --cameras-out) instead of placing them; eyes are "
                 "turned from metres into the scene's units (a Quake 3 map: 1/32 m)");
  add_floor_options(ms, a->floors);
  ms->add_option("--report", a->report, "JSON report (default: printed)");
  commands.push_back({ms, [a, &common] { return run_measure(*a, common); }});
}

pipeline::BakeOptions bake_options_from_args(const std::vector<std::string>& args) {
  CLI::App app{"viewcells"};
  Common common;
  Commands commands;
  const std::shared_ptr<BakeArgs> a = add_bake_command(app, common, commands);
  std::vector<std::string> reversed = {"bake"};
  reversed.insert(reversed.end(), args.begin(), args.end());
  std::reverse(reversed.begin(), reversed.end());  // CLI11 takes a vector last argument first
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw Error(std::string("bake: ") + e.what());
  }
  check_no_empty_values(*commands.front().app);
  return a->options;
}

void add_pvs_commands(CLI::App& app, const Common& common, Commands& commands) {
  add_pvs_command(app, common, commands);
  add_bake_command(app, common, commands);
  add_measure_command(app, common, commands);
}

}  // namespace viewcells::cli
