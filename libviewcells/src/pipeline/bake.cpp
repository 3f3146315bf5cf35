/// `viewcells bake`: sample, subdivide and merge, cut under the budget, AGVS to the error asked
/// for, write the .pvs (both papers end to end).
#include "viewcells/pipeline/bake.h"

#include "pipeline/hidden_classes.h"
#include "pipeline/measured_stop.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/paths.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pipeline/pvs.h"

namespace viewcells::pipeline {

namespace {

/// Everything the hierarchy depends on, as text: a work directory's hierarchy is reused only
/// when this is unchanged (and the scene's fingerprint matches).
std::string hierarchy_key(const BakeConfig& c, uint32_t max_cells) {
  const SamplerConfig& s = c.sampling;
  const SubdivisionConfig& d = c.subdivision;
  std::ostringstream k;
  k.precision(17);
  k << "viewcells bake hierarchy v3\nscene " << c.scene.path
    << (c.scene.scene ? " in memory " + std::to_string(c.scene.scene->fingerprint()) : std::string()) << " grouping "
    << to_string(c.scene.grouping)
    << " robust " << c.scene.robust << "\nsamples " << s.samples << " segments " << s.target_segments << " seed "
    << s.seed << " recasts " << s.max_recasts << " empty " << static_cast<int>(s.empty_space) << "\nview box "
    << s.view_box.lo.x << ' ' << s.view_box.lo.y << ' ' << s.view_box.lo.z << ' ' << s.view_box.hi.x << ' '
    << s.view_box.hi.y << ' ' << s.view_box.hi.z << "\ncost " << c.model.a << ' ' << c.model.b << ' ' << c.model.c
    << ' ' << c.model.screen_width << ' ' << c.model.screen_height << ' ' << c.model.fov_degrees << "\ncells "
    << max_cells << " ga " << static_cast<int>(d.geometry_aligned) << ' ' << d.ga_candidates << ' '
    << d.max_axis_candidates << (d.exact_candidates ? " exact" : " fast") << " min reduction " << d.min_reduction << " density " << d.density.enabled << ' '
    << d.density.lo << ' ' << d.density.hi << ' ' << d.density.outside << (d.play_space ? " play space" : "") << '\n';
  if (c.merge_agvs)
    k << "merge agvs " << c.merge_agvs->seed << ' ' << c.merge_agvs->max_samples << ' ' << c.merge_agvs->pixel_error << ' '
      << c.merge_agvs->batch_size << (c.merge_agvs->max_seconds > 0 ? " seconds " + fmt(c.merge_agvs->max_seconds, 3) : "")
      << '\n';
  else
    k << "merge samples\n";
  return k.str();
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// The hierarchy: from the work directory when it holds one built with these settings for
/// this scene, else built (and kept there).
SubdivisionFile hierarchy(const BakeConfig& c, LoadedScene& loaded, uint32_t max_cells, BakeResult& out,
                          const Log& log) {
  const std::string key = hierarchy_key(c, max_cells);
  const std::string dir = c.work_dir, vcells = dir + "/hierarchy.vcells", key_path = dir + "/hierarchy.key";
  if (!dir.empty() && std::filesystem::is_regular_file(key_path) && read_text(key_path) == key) {
    SubdivisionFile file = read_merged(vcells);
    if (file.scene_fingerprint == loaded.scene->fingerprint()) {
      out.hierarchy_reused = true;
      log("viewcells: bake: hierarchy of " + std::to_string(file.history->leaf_count) + " cells reused from " + vcells);
      return file;
    }
    log("viewcells: bake: " + vcells + " belongs to another version of the scene: building again");
  }
  BuildConfig b;
  b.scene = c.scene;
  b.sampling = c.sampling;
  b.model = c.model;
  b.subdivision = c.subdivision;
  b.subdivision.max_cells = max_cells;
  b.merge_agvs = c.merge_agvs;
  // The scene already loaded samples the hierarchy, and comes back for AGVS.
  BuildResult built = build(b, std::move(loaded), log);
  loaded = std::move(built.sampling.loaded);
  out.sampling = built.sampling.result.stats;
  if (!dir.empty()) {
    const UnbatchedWrites now;  // a checkpoint: kept even when a later stage fails
    std::filesystem::create_directories(dir);
    write_subdivision(vcells, built.file);
    write_text_file(key_path, key);
    log("viewcells: bake: hierarchy -> " + vcells);
  }
  return std::move(built.file);
}

/// Where the bake's cameras stand (measuring, frame samples, near-object eyes): in the play
/// space when the bake weighs cells by it (on a mesh scene its floors; on a map the same
/// player eyes as the map's own view space gives), else in the scene's view space.
std::shared_ptr<const ViewSpace> camera_space(const BakeConfig& c, const LoadedScene& loaded) {
  return c.subdivision.play_space ? play_view_space(loaded) : loaded.view_space;
}

/// The AGVS PVSs of the view cells `pf` (located by `cells`), continued from the work
/// directory's state when it belongs to them, and saved there. With `cams` and a measured
/// error, the cameras' measurements stop it (BakeConfig::measured_error).
std::vector<std::vector<uint32_t>> sample_pvs(const BakeConfig& c, LoadedScene& loaded, const PvsFile& pf,
                                              const CellLocator& cells, const std::optional<CameraSet>& cams,
                                              BakeResult& out, const Log& log) {
  AgvsConfig agvs = c.agvs;
  (c.subdivision.play_space ? play_view_space(loaded) : loaded.view_space)->restrict(agvs);
  out.agvs_in_view_space = static_cast<bool>(agvs.view_space);
  AgvsSolver solver(*loaded.scene, *loaded.caster, cells, agvs);
  const uint64_t identity = pvs_state_identity(loaded.scene->fingerprint(), pf);
  const std::string state = c.work_dir.empty() ? std::string() : c.work_dir + "/pvs.vagvs";
  if (!state.empty() && std::filesystem::is_regular_file(state)) {
    try {
      solver.load(state, identity);
      out.agvs_resumed = true;
      log("viewcells: bake: AGVS continues from " + state + " after " + std::to_string(solver.stats().samples) +
          " samples");
    } catch (const Error& e) {
      log(std::string("viewcells: bake: not continuing from the saved state: ") + e.what());
    }
  }
  log("viewcells: bake: PVSs of " + std::to_string(cells.cell_count()) + " view cells by AGVS");
  // With a work directory, the state is saved every checkpoint_seconds: the run stops between
  // batches, saves, and goes on, which changes nothing of its samples (a resumed state
  // continues exactly), so a bake cut off mid-way continues from the last checkpoint.
  const AgvsConfig& a = c.agvs;
  const MeasuredTarget target{c.measured_error, c.holes};
  if (cams && target.any()) {
    // Measured at every doubling of the samples; the state is saved before each measurement.
    const SolverMeasuring m{*loaded.scene, *loaded.caster, *cams, c.frame};
    out.measured_stop = run_to_measured_error(solver, a, target, m, out.measured_curve, log, [&] {
      if (state.empty()) return;
      const UnbatchedWrites now;
      solver.save(state, identity);
    });
  }
  while (!(cams && target.any())) {
    const double until = solver.stats().seconds + c.checkpoint_seconds;
    const bool sliced = !state.empty() && c.checkpoint_seconds > 0 && (!(a.max_seconds > 0) || until < a.max_seconds);
    solver.set_limits(a.max_samples, sliced ? until : a.max_seconds, a.pixel_error);
    solver.run();
    if (!state.empty()) {
      const UnbatchedWrites now;
      solver.save(state, identity);
    }
    if (!sliced || solver.stats().stop_reason != "reached the time limit") break;
    log("viewcells: bake: checkpoint after " + std::to_string(solver.stats().samples) + " samples -> " + state);
  }
  out.agvs = solver.stats();
  if (out.measured_stop)
    out.agvs.stop_reason = c.holes > 0 ? "measured: " + target.describe() + " (" +
                                             std::to_string(cams->cameras.size()) + " cameras)"
                                       : "measured pixel error at most " + fmt(c.measured_error, 3) + " (mean of " +
                                             std::to_string(cams->cameras.size()) + " cameras)";
  out.pixel_error = solver.pixel_error();
  out.pixel_error_bound = solver.pixel_error_bound();
  std::vector<std::vector<uint32_t>> lists(cells.cell_count());
  for (uint32_t i = 0; i < cells.cell_count(); ++i) lists[i] = solver.pvs().list(i);
  return lists;
}

}  // namespace

std::vector<std::vector<uint32_t>> coarsen(const MergeHistory& h, const std::vector<int32_t>& fine,
                                           const std::vector<std::vector<uint32_t>>& fine_lists,
                                           const std::vector<int32_t>& coarse) {
  std::vector<int32_t> slot(h.nodes.size(), -1);
  for (size_t i = 0; i < coarse.size(); ++i) slot[coarse[i]] = static_cast<int32_t>(i);
  std::vector<std::vector<uint32_t>> lists(coarse.size());
  for (size_t i = 0; i < fine.size(); ++i) {
    int32_t n = fine[i];
    while (n >= 0 && slot[n] < 0) n = h.nodes[n].parent;
    VC_CHECK(n >= 0);
    auto& l = lists[slot[n]];
    l.insert(l.end(), fine_lists[i].begin(), fine_lists[i].end());
  }
  for (auto& l : lists) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
  }
  return lists;
}

namespace {

/// The bytes of a cut's .pvs: the whole file, and its compressed PVS lists alone.
struct CutBytes {
  uint64_t file = 0, lists = 0;
  std::shared_ptr<const PvsFile> pvs;  ///< the file's content, when written (or kept in memory)
  uint64_t budgeted(bool lists_only) const { return lists_only ? lists : file; }
};

/// The .pvs of the view cells `set` with the PVSs `lists`: written, read back and compared
/// (`check`), or only measured (the sizes a search tries).
CutBytes write_cut(const std::string& path, const SubdivisionFile& file, const ViewCellSet& set,
                   const std::vector<std::vector<uint32_t>>* lists, bool check, const Box3& view_box) {
  PvsFile pf = pvs_file_for(file, set);
  pf.bsp.view_box = view_box;
  pf.rule += "; PVS by agvs";
  if (lists) pf.pvs = compress_pvs(*file.history, set.cells, *lists);
  CutBytes b;
  b.lists = compact_pvs_bytes(pf.pvs, pf.object_count);
  if (!check || path.empty()) {  // sizing a candidate cut, or a bake kept in memory
    b.file = pvs_file_bytes(pf);
    if (check) b.pvs = std::make_shared<const PvsFile>(std::move(pf));
    return b;
  }
  write_pvs_checked(path, pf, *lists);
  b.file = std::filesystem::file_size(staged_path(path));
  b.pvs = std::make_shared<const PvsFile>(std::move(pf));
  return b;
}

/// The view cells to sample: the count asked for, or under a memory budget the most cells
/// whose file holds within it with the construction samples' PVSs (the BSP that locates the
/// cells takes its share of the bytes, not only the PVSs).
ViewCellSet first_cut(const BakeConfig& c, const SubdivisionFile& file, const Log& log) {
  const MergeHistory& h = *file.history;
  if (c.cells) return extract_by_count(h, std::min<size_t>(c.cells, h.leaf_count));
  ViewCellSet set;
  try {
    set = extract_by_file_size(file, c.memory, c.memory_of_lists);
  } catch (const Error& e) {
    throw Error(c.output, 0, e.what());
  }
  const size_t n = set.cells.size();
  log("viewcells: bake: " + std::to_string(n) + " view cells fit in " + std::to_string(c.memory) +
      " bytes with the hierarchy's PVSs" + (c.memory_of_lists ? " (the compressed lists alone)" : ""));
  return set;
}

/// The output is checked before any work (every front end gets this, not only the command
/// line): its directory exists and is writable, it is not the scene being baked, and it is not
/// inside the work directory, whose files a later run with the same directory reads.
void check_bake_paths(const BakeConfig& c) {
  if (c.output.empty()) return;
  check_output_target(c.output);
  if (!c.scene.scene && !c.scene.path.empty() && same_file(c.output, c.scene.path))
    throw Error(c.output, 0, "is the scene being baked (" + c.scene.path + "): the .pvs would replace it; write it elsewhere");
  if (!c.work_dir.empty() && inside_directory(c.output, c.work_dir))
    throw Error(c.output, 0, "is inside the work directory " + c.work_dir +
                                 ", whose files later runs with it read: write the .pvs elsewhere");
}

/// The settings a bake refuses, before any work (after resolve(): a stop rule and the measuring
/// cameras a measured stop needs are there by then).
void check_bake(const BakeConfig& c) {
  if ((c.cells > 0) == (c.memory > 0)) throw Error("bake needs one budget: --cells N or --memory BYTES");
  if (!(c.measured_error >= 0) || !std::isfinite(c.measured_error))
    throw Error("the measured pixel error must be a finite number >= 0");
  if (!(c.holes >= 0 && c.holes <= 1)) throw Error("the share of frames with holes must be from 0 to 1");
  if (c.measure_cameras) check_frame_budget(c.measure_cameras, c.frame.width, c.frame.height);
  if (c.frame_samples) check_frame_budget(c.frame_samples, c.sample_frame.width, c.sample_frame.height);
  if (!(c.max_seconds >= 0) || !std::isfinite(c.max_seconds)) throw Error("the bake's time limit must be finite and >= 0");
  check_bake_paths(c);
  if (c.cells && c.subdivision.max_cells && c.cells > c.subdivision.max_cells)
    throw Error("--cells " + std::to_string(c.cells) + " asks for more view cells than the " +
                std::to_string(c.subdivision.max_cells) + " elementary cells of --max-cells: raise --max-cells or "
                "lower --cells");
}

/// Frames as a sampler (BakeConfig::frame_samples), after AGVS: every object a frame shows
/// joins its cell's PVS in `lists`.
void frame_sample_rounds(const BakeConfig& c, const LoadedScene& loaded, const CellLocator& covered_cells,
                         uint64_t sampling_frames, std::vector<std::vector<uint32_t>>& lists, BakeResult& out,
                         const Log& log) {
  // Frames where viewers are, from a seed of their own (the measuring cameras' is c.cameras.seed).
  // After the first round, only the cells whose frames still added something get more: about
  // as many frames again, drawn from the same distribution and kept where they land in those.
  Stopwatch sw;
  std::vector<uint8_t> active(lists.size(), 1);
  std::string rule;
  for (uint32_t round = 0; round < c.frame_rounds; ++round) {
    const size_t n_active = static_cast<size_t>(std::count(active.begin(), active.end(), 1));
    if (n_active == 0 || c.sample_frame.deadline.passed()) break;
    CameraConfig sc = c.cameras;
    sc.count = static_cast<uint32_t>(std::min<uint64_t>(sampling_frames * lists.size() / n_active, 10'000'000));
    sc.seed = c.cameras.seed + 0x5a3'0001 + round;
    const CameraSet drawn = camera_space(c, loaded)->cameras(
        *loaded.scene, *loaded.caster, sc, [&covered_cells](const Vec3& p) { return covered_cells.cell_at(p); },
        &covered_cells);
    rule = drawn.rule;
    std::vector<Camera> kept;
    std::vector<int32_t> kept_cells;
    for (size_t i = 0; i < drawn.cameras.size() && kept.size() < sampling_frames; ++i)
      if (drawn.cells[i] >= 0 && active[static_cast<size_t>(drawn.cells[i])]) {
        kept.push_back(drawn.cameras[i]);
        kept_cells.push_back(drawn.cells[i]);
      }
    std::vector<size_t> before(lists.size());
    for (size_t i = 0; i < lists.size(); ++i) before[i] = lists[i].size();
    const uint64_t added = add_frame_samples(*loaded.caster, kept, kept_cells, c.sample_frame, lists);
    for (size_t i = 0; i < lists.size(); ++i) active[i] = active[i] && lists[i].size() > before[i];
    out.frame_sample_cameras += kept.size();
    out.frame_sample_entries += added;
    if (c.frame_rounds > 1)
      log("viewcells: bake: frame round " + std::to_string(round + 1) + ": " + std::to_string(kept.size()) +
          " frames in " + std::to_string(n_active) + " cells added " + std::to_string(added) + " entries");
  }
  out.frame_sample_seconds = sw.seconds();
  log("viewcells: bake: " + std::to_string(out.frame_sample_cameras) + " sampling frames of " +
      std::to_string(c.sample_frame.width) + "x" + std::to_string(c.sample_frame.height) + " (" + rule +
      ") added " + std::to_string(out.frame_sample_entries) + " PVS entries in " + fmt(out.frame_sample_seconds, 1) +
      " s");
}

/// Near-object samples (BakeConfig::near), after AGVS and the frames, within the bake's time
/// limit as measured by `total`.
void near_object_samples(const BakeConfig& c, const LoadedScene& loaded, const CellLocator& covered_cells,
                         const Stopwatch& total, std::vector<std::vector<uint32_t>>& lists, BakeResult& out,
                         const Log& log) {
  // Viewpoints where viewers are, from a seed of their own, grouped by cell.
  Stopwatch sw;
  CameraConfig ec = c.cameras;
  ec.count = static_cast<uint32_t>(std::min<uint64_t>(uint64_t{c.near_eyes} * lists.size(), 10'000'000));
  ec.seed = c.cameras.seed + 0x6e65'0001;
  // Bake's default: where no viewpoint can be placed (a view box inside solids, a map whose
  // floors cannot be found), the bake goes on without them and says so.
  CameraSet drawn;
  try {
    drawn = camera_space(c, loaded)->cameras(*loaded.scene, *loaded.caster, ec,
                                       [&covered_cells](const Vec3& p) { return covered_cells.cell_at(p); },
                                       &covered_cells);
  } catch (const Interrupted&) {
    throw;
  } catch (const Error& e) {
    out.near_skipped = e.what();
    log("viewcells: bake: near-object samples skipped: no viewpoints (" + out.near_skipped + ")");
  }
  std::vector<std::vector<Vec3>> eyes(lists.size());
  for (size_t i = 0; i < drawn.cameras.size(); ++i)
    if (drawn.cells[i] >= 0) eyes[static_cast<size_t>(drawn.cells[i])].push_back(drawn.cameras[i].eye);
  NearSampleConfig nc = c.near;
  nc.seed = c.agvs.seed;
  if (c.max_seconds > 0) nc.max_seconds = std::max(c.max_seconds - total.seconds(), 1e-9);
  out.near = add_near_samples(*loaded.scene, *loaded.caster, eyes, nc, lists);
  out.near_eyes = drawn.cameras.size();
  out.near_seconds = sw.seconds();
  std::string rounds;
  for (size_t i = 0; i < out.near.added_by_round.size() && out.near_skipped.empty(); ++i)
    rounds += (rounds.empty() ? "" : ", ") + std::to_string(out.near.added_by_round[i]) +
              (out.near.rays_by_round[i] < c.near.rays_per_object
                   ? " (" + std::to_string(out.near.rays_by_round[i]) + " rays a candidate)"
                   : std::string());
  if (out.near_skipped.empty())
    log("viewcells: bake: near-object samples (" + drawn.rule + ", " + std::to_string(out.near_eyes) +
      " viewpoints; neighbours within " + fmt(out.near.distance, 3) + "): " + std::to_string(out.near.tested) +
      " objects tested with " + std::to_string(out.near.rays) + " rays added " + std::to_string(out.near.added) +
      " PVS entries (by round: " + rounds + ") in " + fmt(out.near_seconds, 2) + " s" +
      (out.near.stopped_by_time ? " (stopped at the time limit)" : ""));
}

/// The view cells written, their PVSs and the file's bytes.
struct Written {
  ViewCellSet cells;
  std::vector<std::vector<uint32_t>> lists;
  CutBytes bytes;
};

/// The cut `set` with its PVSs `lists` written; under a memory budget that it exceeds, the
/// largest coarser cut that fits, with the unions of the PVSs.
Written fit_budget(const BakeConfig& c, const SubdivisionFile& file, const ViewCellSet& set,
                   const std::vector<std::vector<uint32_t>>& lists, const Box3& written_box, const Log& log) {
  const MergeHistory& h = *file.history;
  Written w{set, lists, {}};
  w.bytes = write_cut(c.output, file, set, &lists, true, written_box);
  const uint64_t used = w.bytes.budgeted(c.memory_of_lists);
  if (c.memory && used > c.memory) {
    // AGVS found more than the construction samples: the largest coarser cut that fits, with
    // the unions of the sampled PVSs.
    log("viewcells: bake: " + std::to_string(used) + " bytes for " + std::to_string(set.cells.size()) +
        " cells exceed the budget of " + std::to_string(c.memory) + ": coarsening");
    const size_t n = largest_fitting(h.min_cells(), set.cells.size() - 1, c.memory, [&](size_t count) {
      const ViewCellSet cut = extract_by_count(h, count);
      const auto coarse = coarsen(h, set.cells, lists, cut.cells);
      return write_cut(c.output, file, cut, &coarse, false, written_box).budgeted(c.memory_of_lists);
    });
    if (n == 0)
      throw Error(c.output, 0, "not even " + std::to_string(h.min_cells()) + " view cell(s) fit in " +
                                   std::to_string(c.memory) + " bytes");
    w.cells = extract_by_count(h, n);
    w.lists = coarsen(h, set.cells, lists, w.cells.cells);
    w.bytes = write_cut(c.output, file, w.cells, &w.lists, true, written_box);
  }
  return w;
}

/// The PVSs written, measured by the cameras `cams` (again, unless AGVS's last measurement was
/// of these very PVSs).
void measure_written(const BakeConfig& c, const LoadedScene& loaded, const SubdivisionFile& file,
                     const ViewCellSet& set, const Written& w, const Box3& written_box, const CameraSet& cams,
                     BakeResult& out, const Log& log) {
  const bool last_whole = !out.measured_curve.empty() &&
                          out.measured_curve.back().measured.cameras == out.measured_curve.back().measured.cameras_asked;
  if (w.cells.cells.size() == set.cells.size() && last_whole && !c.frame_samples && !c.near.rays_per_object) {
    out.measured = out.measured_curve.back().measured;  // the PVSs written, measured last
  } else {
    // The cells written (coarser when the budget coarsened them): each camera's is found again.
    CameraSet in_written = cams;
    if (w.cells.cells.size() != set.cells.size()) {
      PvsFile wf = pvs_file_for(file, w.cells);
      wf.bsp.view_box = written_box;
      const CellLocator located(wf.bsp, wf.leaf_cell, wf.pvs.cell_count);
      for (size_t i = 0; i < in_written.cameras.size(); ++i)
        in_written.cells[i] = located.cell_at(in_written.cameras[i].eye);
    }
    Stopwatch sw;
    out.measured = measure_frames(*loaded.scene, *loaded.caster, in_written.cameras, in_written.cells,
                                  GlobalPvs::from_lists(file.object_count, w.lists), c.frame);
    out.measured->wrong.clear();
    const PixelErrorMeasure& m = *out.measured;
    if (m.cameras == 0) {
      log("viewcells: bake: the written PVSs are not measured: the time limit (--time) ran out before the first of " +
          std::to_string(m.cameras_asked) + " frames");
      out.measured.reset();
      return;
    }
    log("viewcells: bake: measured pixel error " + fmt(m.pixels, 3) + " (median camera " + fmt(m.median_pixels, 3) +
        ") in " + fmt(sw.seconds(), 1) + " s" +
        (m.cameras < m.cameras_asked ? " over the first " + std::to_string(m.cameras) + " of " +
                                           std::to_string(m.cameras_asked) + " frames: the time limit (--time) ran out"
                                     : std::string()));
  }
}

/// The BSP of the view cells `pf`, over the box the written file covers.
Subdivision covered_cells_bsp(const PvsFile& pf, const Box3& written_box) {
  Subdivision s = pf.bsp;
  s.view_box = written_box;
  return s;
}

/// The bake's last line.
void log_bake(const BakeConfig& c, const BakeResult& out, const Log& log) {
  const double err = out.pixel_error, bound = out.pixel_error_bound;
  log("viewcells: bake: " + std::to_string(out.cells) + " view cells, mean PVS " + fmt(out.mean_pvs, 1) +
      " objects, estimated pixel error " +
      (!std::isnan(err)     ? fmt(err, 2)
       : !std::isnan(bound) ? "below " + fmt(bound, 2) + " (90% bound)"
                            : std::string("not known")) +
      (out.measured ? ", measured " + fmt(out.measured->pixels, 2) + " (median camera " +
                          fmt(out.measured->median_pixels, 2) + ")"
                    : std::string()) +
      " after " + std::to_string(out.agvs.samples) + " samples (" + out.agvs.stop_reason + "); " +
      (c.output.empty() ? std::string("in memory") : c.output) + ": " +
      std::to_string(out.file_bytes) + " bytes in " + fmt(out.seconds, 1) + " s");
}

/// Whether the bake weighs cells by the play space (BakeConfig::play_space_where_known): sets it
/// in `run` and out.config, and returns which view space was chosen and why, in words.
std::string choose_play_space(const BakeConfig& c, const LoadedScene& loaded, BakeConfig& run, BakeResult& out,
                              const Log& log) {
  const std::string scene_space = loaded.view_space->describe();
  if (c.subdivision.play_space) return "the play space (asked for)";
  if (!c.play_space_where_known) return scene_space + " (the play space not asked for)";
  if (c.subdivision.density.enabled) return scene_space + " (a density band says where viewers are)";
  if (!c.sampling.view_box.empty()) return scene_space + " (a view box says where viewers are)";
  if (!loaded.view_space->may_know_players()) return scene_space + " (it knows no players)";
  Stopwatch sw;
  const std::shared_ptr<const ViewSpace> play = loaded.view_space->play_space(*loaded.scene, *loaded.caster);
  if (!play) {
    const std::string why = "the whole view box: no play space (" + loaded.view_space->no_play_space_reason() + ")";
    log("viewcells: bake: view space " + why);
    return why;
  }
  run.subdivision.play_space = out.config.subdivision.play_space = true;
  const std::string rule = play->viewpoint_rule();
  log("viewcells: bake: view space: the play space, found in " + fmt(sw.seconds(), 2) + " s" +
      (rule.empty() ? std::string() : ": " + rule));
  return "the play space (where players stand, found by default): " + rule;
}

}  // namespace

SubdivisionConfig bake_subdivision() {
  SubdivisionConfig s;
  s.max_cells = 0;
  return s;
}

BakeConfig resolve(BakeConfig c, std::vector<std::string>* decided) {
  const auto say = [&](const std::string& words) {
    if (decided) decided->push_back(words);
  };
  if (!c.agvs.max_samples && !(c.agvs.max_seconds > 0) && !(c.agvs.pixel_error > 0) && !(c.measured_error > 0) &&
      !(c.holes > 0) && !(c.max_seconds > 0)) {
    c.agvs.pixel_error = 10;
    say("AGVS stops at an estimated pixel error of 10 (of 1024x1024): no other stop was given");
  }
  // Holes are what a player sees at the resolution played: 1,000 frames of 1024x768; a mean
  // error alone keeps 5,000 frames of 64x48 (its estimator's cost).
  const bool by_holes = c.holes > 0;
  if (!c.measure_cameras && (by_holes || c.measured_error > 0)) {
    c.measure_cameras = by_holes ? 1000 : 5000;
    say(std::to_string(c.measure_cameras) + " measuring cameras (for the " +
        (by_holes ? "share of frames with holes" : "measured pixel error") + ")");
  }
  if (c.frame.width == 0 || c.frame.height == 0) {
    c.frame.width = by_holes ? 1024 : 64;
    c.frame.height = by_holes ? 768 : 48;
    if (c.measure_cameras)
      say("measuring frames of " + std::to_string(c.frame.width) + "x" + std::to_string(c.frame.height) +
          (by_holes ? " (holes as a player sees them)" : " (the mean error's estimator)"));
  }
  if (c.merge_on_agvs && !c.merge_agvs) {
    AgvsConfig a;
    a.seed = c.sampling.seed + 7'000'001;  // not the construction samples' stream
    a.max_samples = std::max<uint64_t>(c.sampling.samples, 1);
    a.show_progress = c.agvs.show_progress;
    c.merge_agvs = a;
    say("merging on AGVS's PVSs of the elementary cells, " + std::to_string(a.max_samples) + " samples a run");
  }
  return c;
}

BakeResult bake(const BakeConfig& config, const Log& log) {
  BakeResult out;
  const BakeConfig c = resolve(config, &out.decided);
  check_bake(c);
  Stopwatch total;
  out.config = c;
  // The whole bake's clock (BakeConfig::max_seconds): a quarter for each of the merge's AGVS
  // runs (the hierarchy's only stages without a bound of their own); the later shares are set
  // once the hierarchy is made. Frames stop at the bake's limit unless given an earlier one.
  BakeConfig run = c;
  const Deadline deadline = Deadline::after(c.max_seconds);
  run.frame.deadline = run.sample_frame.deadline = deadline;
  if (c.max_seconds > 0 && run.merge_agvs) {
    const double share = 0.25 * c.max_seconds;
    run.merge_agvs->max_seconds = run.merge_agvs->max_seconds > 0 ? std::min(run.merge_agvs->max_seconds, share) : share;
  }
  out.threads = worker_threads();
  log("viewcells: bake on " + workers_text());
  const uint32_t max_cells = c.subdivision.max_cells ? c.subdivision.max_cells : (c.cells ? 4 * c.cells : 4096);
  LoadedScene loaded = load_scene_for_rays(c.scene, log);
  std::shared_ptr<const HiddenSpace> hidden;
  if (c.prove_hidden || c.conservative) {
    Stopwatch sw;
    std::string why;
    hidden = hidden_space_of(loaded, why);
    if (!hidden && c.conservative)
      throw Error(c.scene.path, 0, "--conservative needs a scene that can prove objects hidden: " + why);
    out.hidden.method = hidden ? hidden->describe() : why;
    log("viewcells: bake: " + (hidden ? "proving hidden objects with " + out.hidden.method + " (portals in " +
                                            fmt(sw.seconds(), 1) + " s)"
                                      : "nothing can be proven hidden: " + why));
  }
  out.view_space_choice = choose_play_space(c, loaded, run, out, log);
  SubdivisionFile file = hierarchy(run, loaded, max_cells, out, log);
  const MergeHistory& h = *file.history;
  out.hierarchy_seconds = total.seconds();
  if (c.max_seconds > 0) {
    const double left = c.max_seconds - total.seconds();
    if (!(left > 0))
      throw Error(c.output, 0, "the time limit of " + fmt(c.max_seconds, 3) + " s ran out in the hierarchy (" +
                                   fmt(total.seconds(), 2) + " s: sampling, subdivision, merging) before any PVS was "
                                   "sampled: give more time, fewer --samples or --max-cells" +
                                   (c.work_dir.empty() ? std::string(", or --work to keep the hierarchy for a rerun")
                                                       : std::string(" (the hierarchy is kept in " + c.work_dir + ")")));
  }
  out.elementary_cells = static_cast<uint32_t>(h.leaf_count);
  out.scene_fingerprint = file.scene_fingerprint;
  out.object_count = file.object_count;
  const ViewCellSet set = first_cut(c, file, log);
  const uint64_t sampling_frames = std::min<uint64_t>(uint64_t{c.frame_samples} * set.cells.size(), 10'000'000);
  if (sampling_frames)  // before AGVS
    check_frame_budget(sampling_frames * std::max(c.frame_rounds, 1u), c.sample_frame.width, c.sample_frame.height);
  const PvsFile sampled = pvs_file_for(file, set);
  const CellLocator cells(sampled.bsp, sampled.leaf_cell, sampled.pvs.cell_count);
  // The file's cells cover every point where a viewer can be (ViewSpace::covered_box), and the
  // cameras are located in them as an engine would.
  const Box3 written_box = loaded.view_space->covered_box(sampled.bsp.view_box);
  Subdivision covered_bsp = sampled.bsp;
  covered_bsp.view_box = written_box;
  const CellLocator covered_cells(std::move(covered_bsp), sampled.leaf_cell, sampled.pvs.cell_count);
  // The proof needs no samples: first, with at most half of the time left (cells it has not
  // begun then prove nothing, which is safe). In the conservative mode it gets nine tenths: the
  // sets shipped are all the proof does not call hidden, so what sampling adds changes them only
  // where rays see what the proof calls hidden, and every cell left unproven ships everything.
  std::optional<CellProof> proved;
  if (hidden)
    proved = prove_cells(c, *hidden, covered_cells_bsp(sampled, written_box), sampled.leaf_cell,
                         sampled.pvs.cell_count,
                         Deadline::after((c.conservative ? 0.9 : 0.5) * (c.max_seconds - total.seconds())));
  if (c.max_seconds > 0) {
    // Each later stage that renders or casts on its own (frame samples, near-object samples, a
    // measurement of the written PVSs) leaves AGVS a quarter less of what is left, down to a
    // half; those stages stop at the bake's limit.
    const double left = std::max(c.max_seconds - total.seconds(), 1e-9);
    const int after = (c.near.rays_per_object ? 1 : 0) + (c.frame_samples ? 1 : 0) + (c.measure_cameras ? 1 : 0);
    const double agvs_left = left * (after == 0 ? 1.0 : after == 1 ? 0.75 : 0.5);
    run.agvs.max_seconds = run.agvs.max_seconds > 0 ? std::min(run.agvs.max_seconds, agvs_left) : agvs_left;
    run.frame.deadline = Deadline::after(agvs_left);  // AGVS's own measurements
  }
  std::optional<CameraSet> cams;
  if (c.measure_cameras) {
    Stopwatch sw;
    CameraConfig cc = c.cameras;
    cc.count = c.measure_cameras;
    cams = camera_space(run, loaded)->cameras(*loaded.scene, *loaded.caster, cc,
                                      [&covered_cells](const Vec3& p) { return covered_cells.cell_at(p); },
                                      &covered_cells);
    out.camera_rule = cams->rule;
    log("viewcells: bake: " + std::to_string(cams->cameras.size()) + " measuring cameras (" + cams->rule + ") in " +
        fmt(sw.seconds(), 2) + " s");
  }
  std::vector<std::vector<uint32_t>> lists = sample_pvs(run, loaded, sampled, cells, cams, out, log);
  run.frame.deadline = deadline;  // from here on, frames stop at the bake's own limit
  if (c.frame_samples) frame_sample_rounds(run, loaded, covered_cells, sampling_frames, lists, out, log);
  if (c.near.rays_per_object) near_object_samples(run, loaded, covered_cells, total, lists, out, log);
  if (hidden) {
    AimedRays aimed;
    if (c.aimed_rays) aimed = aim_at_undecided(c, loaded, *hidden, *proved, covered_cells, lists, deadline, log);
    out.hidden = hidden_classes(c, loaded, *hidden, *proved, aimed, cams, lists, log);
  }
  out.agvs_cells = static_cast<uint32_t>(set.cells.size());
  const Written w = fit_budget(c, file, set, lists, written_box, log);
  if (cams) measure_written(run, loaded, file, set, w, written_box, *cams, out, log);
  out.file = w.bytes.pvs;
  out.file_bytes = w.bytes.file;
  out.list_bytes = w.bytes.lists;
  out.cells = static_cast<uint32_t>(w.cells.cells.size());
  out.rule = w.cells.rule + "; PVS by agvs";
  for (const auto& l : w.lists) out.pvs_entries += l.size();
  out.mean_pvs = static_cast<double>(out.pvs_entries) / out.cells;
  out.seconds = total.seconds();
  log_bake(c, out, log);
  return out;
}

}  // namespace viewcells::pipeline
