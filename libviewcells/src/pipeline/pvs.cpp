/// `viewcells pvs`: the view cells' PVSs by AGVS, SGVS or REF (adaptive-global-visibility-sampling
/// paper), resumable, measured by cameras.
#include "viewcells/pipeline/pvs.h"

#include "pipeline/measured_stop.h"

#include <cmath>
#include <filesystem>

#include "viewcells/core/ranks.h"
#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pipeline/measure.h"

namespace viewcells::pipeline {

uint64_t pvs_state_identity(uint64_t scene_fingerprint, const PvsFile& cells) {
  ByteWriter id;
  id.put(scene_fingerprint);
  id.put_array(cells.leaf_cell);
  id.put_array(cells.cell_mht_node);
  return fnv1a64(id.data());
}

namespace {

void check_config(const PvsConfig& c) {
  if (!(c.measured_error >= 0) || !std::isfinite(c.measured_error))
    throw Error("--measured-error must be a finite number >= 0");
  if (!c.agvs.max_samples && !(c.agvs.max_seconds > 0) && !(c.agvs.pixel_error > 0) && !(c.measured_error > 0))
    throw Error("give when to stop: --pixel-error, --measured-error, --time or --samples");
  if (c.measured_error > 0 && !c.measure_cameras)
    throw Error("--measured-error needs --measure-cameras: the cameras that measure the PVSs");
  if (c.measured_error > 0 && !c.measure_at.empty())
    throw Error("--measured-error chooses its own measurements (every doubling of the samples): drop --measure-at");
  if (!(c.filter.k >= 0) || !std::isfinite(c.filter.k)) throw Error("--filter-k must be a finite number >= 0");
  if (c.filter.k != 1.0 && !c.filter_object_space)
    throw Error("--filter-k sets the object space filter's factor: add --filter");
  if (!c.edited_from.empty() && c.resume.empty())
    throw Error("--edited-from needs --resume: the state computed on that scene, to carry over to --scene");
  if (!c.measure_at.empty() && !c.measure_cameras)
    throw Error("--measure-at needs --measure-cameras: the cameras that measure the PVSs");
  for (size_t i = 1; i < c.measure_at.size(); ++i)
    if (c.measure_at[i] <= c.measure_at[i - 1]) throw Error("--measure-at: sample counts must increase");
}

/// The scenes: the one sampled, and before an edit the one the hierarchy was built from.
struct Scenes {
  Scene scene;
  std::optional<Scene> before;
  std::unique_ptr<RayCaster> caster, caster_before;
};

void load_scenes(const PvsConfig& c, const SubdivisionFile& file, Scenes& s) {
  s.scene = load_scene(c.scene_path, c.grouping);
  // Dynamic edits: the hierarchy and the state belong to the scene before the edit.
  if (!c.edited_from.empty()) {
    s.before.emplace(load_scene(c.edited_from, c.grouping));
    if (s.before->fingerprint() != file.scene_fingerprint)
      throw Error(c.edited_from, 0, "is not the scene " + c.hierarchy_path + " was built from (fingerprints differ)");
  } else if (s.scene.fingerprint() != file.scene_fingerprint) {
    throw Error(c.scene_path, 0,
                "is not the scene " + c.hierarchy_path + " was built from (fingerprints differ; after editing the "
                "scene, give the original with --edited-from)");
  }
  EmbreeConfig ec;
  ec.robust = c.robust;
  s.caster = make_embree_caster(s.scene, ec);
}

/// The solver, fresh, resumed, or resumed on the scene before an edit and then edited.
void make_solver(const PvsConfig& c, Scenes& s, const CellLocator& cells, const PvsFile& pf, const AgvsConfig& config,
                 std::optional<AgvsSolver>& solver, std::optional<AgvsEditStats>& edit, const Log& log) {
  const uint64_t identity = pvs_state_identity(s.scene.fingerprint(), pf);
  if (s.before && AgvsSolver::state_identity(c.resume) != identity) {
    // The state describes the scene before the edit: load it there, then edit.
    EmbreeConfig ec;
    ec.robust = c.robust;
    s.caster_before = make_embree_caster(*s.before, ec);
    solver.emplace(*s.before, *s.caster_before, cells, config);
    solver->load(c.resume, pvs_state_identity(s.before->fingerprint(), pf));
    log("viewcells: resumed from " + c.resume + " after " + std::to_string(solver->stats().samples) +
        " samples on " + c.edited_from);
    edit = solver->edit(s.scene, *s.caster, match_objects(*s.before, s.scene));
    log("viewcells: edit: " + std::to_string(edit->deleted) + " objects deleted (" +
        std::to_string(edit->removed_deleted) + " PVS entries), " + std::to_string(edit->inserted) + " inserted (" +
        std::to_string(edit->removed_penumbra) + " entries in their penumbrae removed, " +
        std::to_string(edit->cells_cleared) + " cells they touch emptied)");
    return;
  }
  solver.emplace(s.scene, *s.caster, cells, config);
  if (!c.resume.empty()) {
    solver->load(c.resume, identity);
    log("viewcells: resumed from " + c.resume + " after " + std::to_string(solver->stats().samples) + " samples");
  }
}

void add_references(const PvsConfig& c, const PvsFile& pf, AgvsSolver& solver) {
  for (const std::string& path : c.references) {
    const PvsFile ref = read_pvs(path);
    if (ref.pvs.cell_count != pf.pvs.cell_count || ref.object_count != pf.object_count ||
        ref.scene_fingerprint != pf.scene_fingerprint || ref.leaf_cell != pf.leaf_cell)
      throw Error(path, 0, "is not a .pvs of these view cells of this scene");
    std::vector<std::vector<uint32_t>> lists(ref.pvs.cell_count);
    for (uint32_t i = 0; i < ref.pvs.cell_count; ++i) lists[i] = ref.pvs.cell_pvs(i);
    solver.add_reference(GlobalPvs::from_lists(pf.object_count, lists));
  }
}

/// The cameras that measure the pixel error: player eyes on a Quake 3 map, else random points
/// of the view box (as the estimator's cameras).
CameraSet measuring_cameras(const PvsConfig& c, const Scenes& s, const ViewSpace& space, const CellLocator& cells) {
  CameraConfig cc;
  cc.count = c.measure_cameras;
  cc.seed = c.agvs.seed + 17;
  return space.cameras(s.scene, *s.caster, cc, [&cells](const Vec3& p) { return cells.cell_at(p); }, &cells);
}

FrameConfig measuring_frame(const PvsConfig& c, const PvsResult& out) {
  return FrameConfig{c.measure_size, c.measure_size, 90.0, out.agvs.resolution};
}

SolverMeasuring measuring(const PvsConfig& c, const Scenes& s, const CameraSet& cams, const PvsResult& out) {
  return SolverMeasuring{s.scene, *s.caster, cams, measuring_frame(c, out)};
}

/// Runs the solver up to each of c.measure_at and measures its PVSs there.
void measured_run(const PvsConfig& c, const Scenes& s, const CameraSet& cams, AgvsSolver& solver, PvsResult& out,
                  const Log& log) {
  const AgvsConfig& a = c.agvs;
  for (uint64_t n : c.measure_at) {
    if (a.max_samples && n > a.max_samples) break;
    solver.set_limits(n, a.max_seconds, 0);
    solver.run();
    out.measured_curve.push_back(measure_solver(measuring(c, s, cams, out), solver, log));
    if (a.max_seconds > 0 && solver.stats().seconds >= a.max_seconds) break;
  }
  solver.set_limits(a.max_samples, a.max_seconds, a.pixel_error);
}

/// Measures the pixel error of the PVSs written (and of the unfiltered ones, when filtered).
void measure(const PvsConfig& c, const Scenes& s, const CameraSet& cams, const AgvsSolver& solver,
             const GlobalPvs& written, PvsResult& out, const Log& log) {
  Stopwatch ms;
  auto run = [&](const GlobalPvs& pvs) {
    PixelErrorMeasure m = measure_frames(s.scene, *s.caster, cams.cameras, cams.cells, pvs, measuring_frame(c, out));
    m.wrong.clear();
    return m;
  };
  out.measured = run(written);
  if (out.filtering) out.measured_unfiltered = run(solver.pvs());
  log("viewcells: measured pixel error " + fmt(out.measured->pixels, 2) +
      (out.filtering ? " (unfiltered " + fmt(out.measured_unfiltered->pixels, 2) + ")" : std::string()) + " of " +
      std::to_string(out.agvs.resolution) + " pixels (" + std::to_string(out.measured->cameras) + " cameras of " +
      std::to_string(c.measure_size) + "x" + std::to_string(c.measure_size) + ": " + cams.rule + "; " +
      fmt(ms.seconds(), 1) + " s)");
}

std::string describe_stop(const PvsConfig& c) {
  const AgvsConfig& a = c.agvs;
  return (c.measured_error > 0 ? "a measured pixel error of " + fmt(c.measured_error, 2) + " " : std::string()) +
         (a.pixel_error > 0 ? "an estimated pixel error of " + fmt(a.pixel_error, 2) + " " : std::string()) +
         (a.max_seconds > 0 ? fmt(a.max_seconds, 1) + " s " : std::string()) +
         (a.max_samples ? std::to_string(a.max_samples) + " samples" : std::string());
}

}  // namespace

MeasuredPoint measure_solver(const SolverMeasuring& m, const AgvsSolver& solver, const Log& log) {
  const AgvsStats& st = solver.stats();
  MeasuredPoint p;
  p.samples = st.samples;
  p.rays = st.rays;
  p.seconds = st.seconds;
  p.mean_pvs = solver.mean_pvs();
  p.estimated = solver.pixel_error();
  p.measured = measure_frames(m.scene, m.caster, m.cameras.cameras, m.cameras.cells, solver.pvs(), m.frame);
  p.measured.wrong.clear();
  log("viewcells: after " + std::to_string(p.samples) + " samples (" + fmt(p.seconds, 2) + " s): measured pixel error " +
      fmt(p.measured.pixels, 3) + " (median camera " + fmt(p.measured.median_pixels, 3) + ")");
  return p;
}

bool MeasuredTarget::met(const PixelErrorMeasure& m) const {
  return any() && (!(mean > 0) || m.pixels <= mean) && (!(holes > 0) || m.wrong_frame_share() <= holes);
}

std::string MeasuredTarget::describe() const {
  std::string s;
  if (holes > 0) s = "at most " + fmt(100 * holes, 2) + "% of frames with a wrong pixel";
  if (mean > 0) s += (s.empty() ? "" : " and ") + std::string("a mean of at most ") + fmt(mean, 3) + " wrong pixels";
  return s;
}

namespace {

/// Seconds of sampling until `value` (falling as a power of the time through the last two
/// measurements) reaches `target`: 0 when it has, NaN when two points do not tell.
double seconds_to(double t0, double v0, double t1, double v1, double target) {
  if (v1 <= target) return 0;
  if (!(t0 > 0 && t1 > t0 && v0 > 0 && v1 > 0 && v1 < v0)) return std::nan("");
  const double slope = std::log(v1 / v0) / std::log(t1 / t0);  // < 0
  return t1 * std::pow(target / v1, 1 / slope) - t1;
}

/// The time left for `target` from the curve's last two points: the longest over its parts.
double eta(const std::vector<MeasuredPoint>& curve, const MeasuredTarget& target) {
  if (curve.size() < 2) return std::nan("");
  const MeasuredPoint& a = curve[curve.size() - 2];
  const MeasuredPoint& b = curve.back();
  const double mean = target.mean > 0
                          ? seconds_to(a.seconds, a.measured.pixels, b.seconds, b.measured.pixels, target.mean)
                          : 0.0;
  const double holes = target.holes > 0
                           ? seconds_to(a.seconds, a.measured.wrong_frame_share(), b.seconds, b.measured.wrong_frame_share(),
                                      target.holes)
                           : 0.0;
  return std::isnan(mean) || std::isnan(holes) ? std::nan("") : std::max(mean, holes);
}

}  // namespace

bool run_to_measured_error(AgvsSolver& solver, const AgvsConfig& a, const MeasuredTarget& target,
                           const SolverMeasuring& m, std::vector<MeasuredPoint>& curve, const Log& log,
                           const std::function<void()>& after_run) {
  uint64_t next = std::max<uint64_t>(solver.stats().samples + 1, a.batch_size);
  while (true) {
    const uint64_t until = a.max_samples ? std::min(next, a.max_samples) : next;
    solver.set_limits(until, a.max_seconds, a.pixel_error);
    solver.run();
    if (after_run) after_run();
    const AgvsStats& st = solver.stats();
    curve.push_back(measure_solver(m, solver, log));
    MeasuredPoint& now = curve.back();
    if (now.measured.cameras < now.measured.cameras_asked) {  // the frame deadline cut it
      log("viewcells: the time limit ran out while measuring (" + std::to_string(now.measured.cameras) + " of " +
          std::to_string(now.measured.cameras_asked) + " frames): sampling stops here");
      return false;
    }
    if (target.met(now.measured)) {
      now.eta_seconds = 0;
      return true;
    }
    now.eta_seconds = eta(curve, target);
    log("viewcells: " + fmt(100.0 * now.measured.wrong_frame_share(), 2) +
        "% of frames with a wrong pixel, mean " + fmt(now.measured.pixels, 3) + " (target: " + target.describe() +
        "); " +
        (std::isnan(now.eta_seconds) ? std::string("time left not known yet")
                                     : "about " + fmt(now.eta_seconds, now.eta_seconds < 10 ? 2 : 0) +
                                           " s of sampling left at this rate (measuring not counted)"));
    // Another limit: the samples, the time, or the estimator's error (the solver's own stop).
    const double estimated = solver.pixel_error(), bound = solver.pixel_error_bound();
    if (st.samples < until || (a.max_samples && st.samples >= a.max_samples) ||
        (a.max_seconds > 0 && st.seconds >= a.max_seconds) ||
        (a.pixel_error > 0 && ((!std::isnan(estimated) && estimated <= a.pixel_error) ||
                               (!std::isnan(bound) && bound <= a.pixel_error))))
      return false;
    next = 2 * st.samples;
  }
}

std::vector<RankPhases> gather_phases(const AgvsStats& stats) {
  RankPhases mine{stats.draw_seconds, stats.mutation_seconds, stats.cast_seconds, stats.apply_seconds,
                  ranks::traffic().seconds};
  std::vector<std::string> items(static_cast<size_t>(ranks::size()));
  ByteWriter w;
  w.put(mine);
  items[static_cast<size_t>(ranks::rank())] = w.take();
  ranks::share(items, [](size_t i) { return static_cast<int>(i); });
  std::vector<RankPhases> all;
  for (const std::string& item : items) {
    ByteReader r(item, "a rank's phases");
    all.push_back(r.get<RankPhases>());
  }
  return all;
}

PvsResult compute_pvs(const PvsConfig& c, const Log& log) {
  check_config(c);
  PvsResult out;
  out.config = c;
  out.threads = worker_threads();
  out.agvs = c.agvs;
  out.agvs.filter_statistics = c.filter_object_space || c.filter.view_neighbours > 0;
  out.filtering = out.agvs.filter_statistics;
  const SubdivisionFile file = read_merged(c.hierarchy_path);
  const MergeHistory& h = *file.history;
  CutRule cut;
  cut.count = c.cells;
  const ViewCellSet set = choose_cells(file, cut, true);
  Stopwatch sw;
  Scenes scenes;
  load_scenes(c, file, scenes);
  PvsFile pf = pvs_file_for(file, set);
  pf.rule += "; PVS by " + std::string(to_string(c.agvs.method));
  // The PVSs name the objects of the scene sampled (the edited one, after an edit).
  pf.object_count = static_cast<uint32_t>(scenes.scene.object_count());
  pf.object_names.clear();
  for (const ObjectInfo& o : scenes.scene.objects) pf.object_names.push_back(o.name);
  pf.scene_fingerprint = scenes.scene.fingerprint();
  const CellLocator cells(pf.bsp, pf.leaf_cell, pf.pvs.cell_count);
  out.setup_seconds = sw.seconds();
  out.rule = set.rule;
  out.cells = cells.cell_count();
  log("viewcells: " + std::to_string(cells.cell_count()) + " view cells (" + set.rule + "), PVS by " +
      to_string(c.agvs.method) + " until " + describe_stop(c) + ", on " + workers_text());
  // AGVS's points are drawn in the scene's view space (on a Quake 3 map its non-solid space),
  // and cameras stand where it places them (on a map, where players do).
  const std::shared_ptr<const ViewSpace> space = view_space_of(read_level_data(c.scene_path));
  space->restrict(out.agvs);
  // The file's cells cover every point where a viewer can be (ViewSpace::covered_box): the
  // cameras are located in them as an engine would.
  const Box3 written_box = space->covered_box(pf.bsp.view_box);
  Subdivision covered_bsp = pf.bsp;
  covered_bsp.view_box = written_box;
  const CellLocator covered_cells(std::move(covered_bsp), pf.leaf_cell, pf.pvs.cell_count);
  std::optional<CameraSet> cams;
  if (c.measure_cameras) {
    cams = measuring_cameras(c, scenes, *space, covered_cells);
    out.camera_rule = cams->rule;
  }
  std::optional<AgvsSolver> solver;
  make_solver(c, scenes, cells, pf, out.agvs, solver, out.edit, log);
  add_references(c, pf, *solver);
  if (!c.save.empty() && c.save_every > 0) {
    // Checkpoints: installed at once (a later failure must not take them back), written by
    // rank 0 alone on a cluster (every rank holds the same state).
    const uint64_t identity = pvs_state_identity(scenes.scene.fingerprint(), pf);
    solver->set_checkpoint(c.save_every, [&, identity] {
      if (!ranks::writer()) return;
      UnbatchedWrites now;
      solver->save(c.save, identity);
    });
  }
  bool measured_stop = false;
  if (cams && c.measured_error > 0) {
    measured_stop = run_to_measured_error(*solver, c.agvs, MeasuredTarget{c.measured_error, 0},
                                          measuring(c, scenes, *cams, out),
                                          out.measured_curve, log);
  } else {
    if (cams && !c.measure_at.empty()) measured_run(c, scenes, *cams, *solver, out, log);
    solver->run();
  }
  if (!c.save.empty()) {
    solver->save(c.save, pvs_state_identity(scenes.scene.fingerprint(), pf));
    log("viewcells: state -> " + c.save + " (continue with --resume)");
  }
  out.stats = solver->stats();
  out.rank_phases = gather_phases(out.stats);
  if (measured_stop)
    out.stats.stop_reason = "measured pixel error at most " + fmt(c.measured_error, 3) + " (mean of " +
                            std::to_string(c.measure_cameras) + " cameras)";
  // The sampled PVSs (filtered, when asked) replace the construction ones, compressed through
  // the hierarchy.
  VisibilityFilter filter = c.filter;
  filter.object_space = c.filter_object_space;
  std::vector<std::vector<uint32_t>> lists(cells.cell_count());
  if (out.filtering) {
    lists = solver->filtered_pvs(filter);
  } else {
    for (uint32_t i = 0; i < cells.cell_count(); ++i) lists[i] = solver->pvs().list(i);
  }
  const GlobalPvs written = GlobalPvs::from_lists(pf.object_count, lists);
  out.mean_pvs = solver->mean_pvs();
  out.mean_written = static_cast<double>(written.entries()) / cells.cell_count();
  out.pvs_entries = solver->pvs().entries();
  if (out.filtering)
    log("viewcells: visibility filter (" +
        std::string(c.filter_object_space ? "object space, k = " + fmt(c.filter.k, 2) : "") +
        (c.filter_object_space && c.filter.view_neighbours ? ", " : "") +
        (c.filter.view_neighbours ? "view space, " + std::to_string(c.filter.view_neighbours) + " neighbours" : "") +
        "): mean PVS " + fmt(out.mean_pvs, 1) + " -> " + fmt(out.mean_written, 1) + " objects");
  pf.pvs = compress_pvs(h, set.cells, lists);
  pf.bsp.view_box = written_box;
  write_pvs_checked(c.output, pf, lists);
  out.pixel_error = solver->pixel_error();
  out.pixel_error_bound = solver->pixel_error_bound();
  if (cams && c.measured_error > 0 && !out.filtering) {
    // The rule's last measurement, whatever stopped it, was of the PVSs written.
    out.measured = out.measured_curve.back().measured;
  } else if (cams) {
    measure(c, scenes, *cams, *solver, written, out, log);
  }
  const double err = out.pixel_error, bound = out.pixel_error_bound;
  log("viewcells: " + std::to_string(out.stats.samples) + " samples (" + std::to_string(out.stats.rays) + " rays) in " +
      fmt(out.stats.seconds, 2) + " s; mean PVS " + fmt(out.mean_pvs, 1) + " objects; estimated pixel error " +
      (!std::isnan(err)     ? fmt(err, 2)
       : !std::isnan(bound) ? "below " + fmt(bound, 2) + " (90% bound: too few wrong camera rays for an estimate)"
                            : std::string("not yet known")) +
      " (" + out.stats.stop_reason + "); -> " + c.output);
  return out;
}

}  // namespace viewcells::pipeline
