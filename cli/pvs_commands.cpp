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

void add_agvs_options(CLI::App* cmd, AgvsOptions& a, bool with_method, const std::string& samples_name,
                      const std::string& time_name = "--time") {
  cmd->add_option("--pixel-error", a.bound.pixel_error,
                  "Stop when the estimated pixel error (pixels of a 1024x1024 image that differ) is at most this")
      ->check(positive());
  cmd->add_option(time_name, a.bound.max_seconds, "Stop AGVS after this many seconds of sampling")->check(positive());
  cmd->add_option(samples_name, a.bound.max_samples,
                  "Stop after this many AGVS samples (checked between batches: a run may pass it by less than a batch)")
      ->check(whole(1, kMaxSamples));
  if (with_method)
    cmd->add_option("--method", a.method, "agvs (adaptive mixture), sgvs (view space-direction only) or ref (per cell)")
        ->capture_default_str();
  cmd->add_option("--batch", a.bound.batch_size, "Samples per batch")->capture_default_str()->check(whole(1, 100'000'000));
  cmd->add_option("--mutation-lanes", a.bound.mutation_lanes,
                  "AGVS: independent lanes of mutation candidates, each with its own random stream and its share of "
                  "the buffer. Lanes are drawn and fed in parallel, on a cluster each by its own rank: give at least "
                  "as many as the cores of all nodes for a bake that scales. The result depends on it, not on the "
                  "threads or ranks")
      ->capture_default_str()
      ->check(whole(1, 65536));
  cmd->add_option("--min-share", a.bound.min_share,
                  "AGVS: share of every batch kept for view space-direction samples whatever their weight; they are "
                  "the pixel error estimator's camera rays (more: a finer estimate, fewer samples for the mutations)")
      ->capture_default_str()
      ->check(in_range(0.0, 1.0));
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
  add_agvs_options(pv, a->agvs, true, "--samples");
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

/// `bake`'s options: those that are a field of the bake's config bind to `bound` (whose defaults
/// are the command line's); the rest are parsed, shared with other commands, or decide a default
/// from what else was given, when the command runs (bake_config).
struct BakeArgs {
  pipeline::BakeConfig bound;
  SamplingOptions sampling;
  CellOptions cells;
  std::string memory, memory_of = "file";
  AgvsOptions agvs;
  MergeOptions merge;
  std::string report;
  std::string holes, measure_size, frame_size = "256x192";
};

/// "1%" or "1" (percent) -> 0.01.
double parse_percent(const std::string& text, const std::string& option) {
  std::string number = text;
  if (!number.empty() && number.back() == '%') number.pop_back();
  const std::vector<double> v = parse_numbers(number, option);
  if (v.size() != 1 || !(v[0] > 0 && v[0] <= 100))
    throw Error(option + " needs a percentage above 0 and at most 100, e.g. 1% (got '" + text + "')");
  return v[0] / 100;
}

/// The bake the options ask for, with the command line's defaults (also what bindings that
/// bake from code run: bake_config_from_args).
pipeline::BakeConfig bake_config(BakeArgs a, const Common& c) {
  pipeline::BakeConfig config = a.bound;
  config.model = a.cells.model();
  config.subdivision = a.cells.subdivision(c, a.sampling);
  config.play_space_where_known = a.cells.play_space_by_default && !a.cells.no_play_space;
  config.scene = a.sampling.source();
  config.sampling = a.sampling.sampler(c);
  config.merge_on_agvs = a.merge.pvs == "agvs";
  config.merge_agvs = a.merge.agvs(c, a.sampling.seed, config.sampling.samples);
  config.memory = a.memory.empty() ? 0 : parse_bytes(a.memory);
  if (!a.memory.empty() && config.memory == 0) throw Error("--memory must be above 0 bytes (got '" + a.memory + "')");
  if (a.memory_of != "file" && a.memory_of != "lists") throw Error("--memory-of is file or lists, not '" + a.memory_of + "'");
  config.memory_of_lists = a.memory_of == "lists";
  config.holes = a.holes.empty() ? 0.0 : parse_percent(a.holes, "--holes");
  // The stop rule, the measuring cameras and their frames when not given: the library decides
  // (pipeline::resolve).
  if (!a.measure_size.empty())
    std::tie(config.frame.width, config.frame.height) = parse_size(a.measure_size, "--measure-size", 2048);
  std::tie(config.sample_frame.width, config.sample_frame.height) = parse_size(a.frame_size, "--frame-size", 2048);
  config.agvs = a.agvs.config(c);
  config.agvs.seed = a.sampling.seed;
  return config;
}

int run_bake(const BakeArgs& a, const Common& c) {
  check_files({a.sampling.scene}, {a.bound.output, a.report}, {a.bound.work_dir});
  ThreadLimit threads(c.threads);
  const pipeline::BakeConfig config = bake_config(a, c);
  const pipeline::BakeResult result = pipeline::bake(config, c.logger());
  write_report_to(a.report, result, c);
  return 0;
}

/// Adds `bake`; returns its parsed options (filled by the parse).
std::shared_ptr<BakeArgs> add_bake_command(CLI::App& app, const Common& common, Commands& commands) {
  auto a = std::make_shared<BakeArgs>();
  a->cells.max_cells = 0;
  a->cells.play_space_by_default = true;
  a->sampling.samples = 1'000'000;
  auto* bk = app.add_subcommand(
      "bake",
      "The whole chain in one command: sample, subdivide and merge, cut view cells under the budget, compute "
      "their PVSs by AGVS to the pixel error asked for, compress and write a .pvs file for the engine");
  add_sampling_options(bk, a->sampling);
  add_floor_options(bk, a->sampling.floors);
  auto* cells = bk->add_option("--cells", a->bound.cells, "Budget: this many view cells")->check(whole(1, kMaxCells));
  bk->add_option("--memory", a->memory,
                 "Budget: a .pvs file of at most this many bytes (K, M, G allowed); the file written is measured, "
                 "and the cells are merged further until it fits")
      ->excludes(cells);
  bk->add_option("--memory-of", a->memory_of,
                 "What --memory counts: file (the whole .pvs) or lists (the visible sets alone as an engine's compact "
                 "handle holds them: the coded lists and 8 bytes a hierarchy node, without point location and object "
                 "names; what stands against a map compiler's vis rows)")
      ->capture_default_str();
  bk->add_option("--max-cells", a->cells.max_cells,
                 "Elementary cells to build before merging (default: 4 x --cells, or 4096 with --memory)")
      ->check(whole(1, kMaxCells));
  add_cell_options(bk, a->cells, "");
  add_merge_options(bk, a->merge);
  add_agvs_options(bk, a->agvs, false, "--agvs-samples", "--agvs-time");
  bk->add_option("--time", a->bound.max_seconds,
                 "Bound the whole bake to this many seconds: each of the merge's two AGVS runs stops at a quarter of "
                 "it, the PVSs' AGVS at three quarters of what is left, the near-object samples when it runs out (a "
                 "hierarchy that uses it all up is an error, and with --work is kept for a rerun). --agvs-time bounds "
                 "the PVSs' AGVS alone")
      ->check(positive());
  bk->add_option("--work", a->bound.work_dir,
                 "Work directory: keeps the hierarchy and the AGVS state, so that a rerun with the same scene and "
                 "settings skips the hierarchy and continues sampling (e.g. with a smaller --pixel-error)");
  bk->add_option("--checkpoint", a->bound.checkpoint_seconds,
                 "With --work: save the AGVS state this often, in seconds, so that a bake cut off continues from "
                 "there when run again (0: only at the end)")
      ->capture_default_str()
      ->check(non_negative());
  bk->add_option("--measured-error", a->bound.measured_error,
                 "Stop AGVS once cameras measure at most this many wrong pixels per 1024x1024 frame (mean over the "
                 "cameras), instead of trusting the estimate: measured after one batch and at every doubling of the "
                 "samples (a run may sample up to twice what it needed; --time and the other limits still apply)")
      ->check(non_negative());
  bk->add_option("--holes", a->holes,
                 "Stop AGVS once at most this percentage of the measuring cameras' frames shows any wrong pixel "
                 "(e.g. 1%): the holes a player sees. Measured after one batch and at every doubling of the samples "
                 "(by default 1,000 cameras of 1024x768, placed as `viewcells measure` places them), each "
                 "measurement logged with an estimate of the time left; with --measured-error both must hold; "
                 "--time still bounds the bake");
  bk->add_option("--frame-samples", a->bound.frame_samples,
                 "After AGVS, frames as a sampler: this many cameras per view cell on average, placed as measuring "
                 "cameras are (on a Quake 3 map player eyes, pitch within 30 degrees) but from a seed of their own, "
                 "render --frame-size frames, and every object a frame shows joins its cell's PVS (0: none)")
      ->check(whole(0, 100000));
  bk->add_option("--frame-size", a->frame_size, "Frames of --frame-samples, WIDTHxHEIGHT")->capture_default_str();
  bk->add_option("--frame-rounds", a->bound.frame_rounds,
                 "Rounds of --frame-samples: after the first, only the cells whose frames still added an object get "
                 "about as many frames again")
      ->capture_default_str()
      ->check(whole(1, 64));
  bk->add_option("--near-samples", a->bound.near.rays_per_object,
                 "After AGVS, near-object samples: every view cell tests each object whose box lies within "
                 "--near-distance of an object of its PVS and that it lacks, with this many rays from its viewpoints "
                 "(placed as measuring cameras are, --near-eyes a cell on average, a seed of their own) to random "
                 "points on the object; the object joins the PVS when a ray reaches it unblocked. They close most "
                 "of the holes AGVS leaves (trims and steps beside what a cell sees) for a few percent of render "
                 "cost; at most 2^31 rays in all (fewer a candidate on scenes with more). 0: none")
      ->capture_default_str()
      ->check(whole(0, 4096));
  bk->add_flag("--conservative", a->bound.conservative,
               "Ship no holes by construction: prove objects hidden through the scene's solid space (a Quake 3 "
               "map's BSP portals, or a mesh's closed convex solids), and add every (cell, object) pair that is "
               "neither seen by a ray nor proven hidden to the PVSs, so that no line from any point of a cell "
               "reaches an object missing from its PVS. Costs more to render than the sampled PVSs (the report's "
               "hidden.cost_per_frame gives both bounds); an error on a scene that can prove nothing hidden");
  bk->add_flag("--prove-hidden,!--no-prove-hidden", a->bound.prove_hidden,
               "Sort every (cell, object) pair into proven visible, proven hidden and undecided, and report the "
               "classes and the render cost of both bounds (the report's \"hidden\"); the PVSs written are unchanged "
               "unless --conservative")
      ->capture_default_str();
  bk->add_option("--proof-steps", a->bound.hidden_max_steps,
                 "Portals one flood of the proof may try; a flood over it keeps all it might still reach (never "
                 "less: only the bound loosens)")
      ->capture_default_str()
      ->check(whole(1, 1000000000));
  bk->add_option("--aimed-rays", a->bound.aimed_rays,
                 "With the proof (--prove-hidden, --conservative): rays aimed at each (view cell, object) pair it "
                 "leaves undecided, from points of the cell's empty space to points of the object, up to this many a "
                 "pair; one that arrives proves the pair visible (0: none)")
      ->capture_default_str()
      ->check(whole(0, 1000000));
  bk->add_option("--near-rounds", a->bound.near.rounds,
                 "Rounds of --near-samples: each round tests the neighbours of what the last one added")
      ->capture_default_str()
      ->check(whole(1, 64));
  bk->add_option("--near-eyes", a->bound.near_eyes, "Viewpoints a cell has on average for --near-samples")
      ->capture_default_str()
      ->check(whole(1, 100000));
  bk->add_option("--near-distance", a->bound.near.distance,
                 "Objects are neighbours for --near-samples when their boxes are at most this far apart (default "
                 "1/1000 of the scene's bounding box diagonal)")
      ->check(non_negative());
  bk->add_option("--measure-size", a->measure_size,
                 "Frames of the measuring cameras, WIDTHxHEIGHT (default 1024x768 with --holes, else 64x48)");
  bk->add_option("--measure-cameras", a->bound.measure_cameras,
                 "Cameras that measure the PVSs, placed and counted as `viewcells measure` does (on a Quake 3 map "
                 "player eyes above floors reachable from the spawn points, else random points of the view box; "
                 "64x48 pixels, seed 1): the report gives the written file's measured pixel error (default: 5000 "
                 "with --measured-error, else none)")
      ->check(whole(1, 1'000'000));
  bk->add_option("-o,--output", a->bound.output, "The .pvs file to write")->required();
  bk->add_option("--report", a->report, "JSON report: budget, cells, file bytes, pixel error, samples, timings");
  bk->footer("Without --pixel-error, --measured-error, --time, --agvs-time or --agvs-samples, AGVS runs to an "
             "estimated pixel error of 10 (of 1024x1024).");
  commands.push_back({bk, [a, &common] {
                        if (a->bound.cells == 0 && a->memory.empty())
                          throw Error("bake needs a budget: --cells N or --memory BYTES");
                        return run_bake(*a, common);
                      }});
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

pipeline::BakeConfig bake_config_from_args(const std::vector<std::string>& args, bool quiet) {
  CLI::App app{"viewcells"};
  Common common;
  common.quiet = quiet;
  Commands commands;
  const std::shared_ptr<BakeArgs> a = add_bake_command(app, common, commands);
  CLI::App& bake = *commands.front().app;
  // Words are checked here, in the caller's order, so that an unknown one is named as given
  // (CLI11 lists leftovers in the order it took them, last first).
  for (const std::string& word : args) {
    if (word.rfind("--", 0) != 0) continue;
    const std::string name = word.substr(0, word.find('='));
    if (name == "--help")
      throw Error("bake: help is not an option of a bake from code; the options are viewcells bake's:\n" +
                  bake.help("", CLI::AppFormatMode::Sub));
    if (!bake.get_option_no_throw(name))
      throw Error("bake: unknown option " + name + " (the options are those of `viewcells bake --help`)");
  }
  std::vector<std::string> reversed = {"bake"};
  reversed.insert(reversed.end(), args.begin(), args.end());
  std::reverse(reversed.begin(), reversed.end());  // CLI11 takes a vector last argument first
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw Error(std::string("bake: ") + e.what());
  }
  check_no_empty_values(*commands.front().app);
  if (a->bound.cells == 0 && a->memory.empty()) throw Error("bake needs a budget: cells or memory");
  return bake_config(*a, common);
}

void add_pvs_commands(CLI::App& app, const Common& common, Commands& commands) {
  add_pvs_command(app, common, commands);
  add_bake_command(app, common, commands);
  add_measure_command(app, common, commands);
}

}  // namespace viewcells::cli
