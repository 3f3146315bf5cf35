#pragma once
/// `viewcells bake`: the whole chain for a shippable result in one call. Sample visibility,
/// subdivide the view space and merge the cells into a history, cut the view cells under the
/// budget, compute their PVSs by AGVS to the pixel error asked for, compress them through
/// the hierarchy and write the .pvs. With a memory budget, the cut is made coarser until the
/// file actually written fits (the AGVS PVSs of merged cells are the unions of their parts).
/// With a work directory, a rerun with the same settings reuses the hierarchy and continues
/// the AGVS state instead of starting over.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "viewcells/agvs/agvs.h"
#include "viewcells/merge/merge.h"
#include "viewcells/pipeline/build.h"
#include "viewcells/pipeline/pvs.h"
#include "viewcells/pvs/near_samples.h"

namespace viewcells::pipeline {

/// The subdivision's settings for a bake: SubdivisionConfig's, with max_cells 0 (from the budget).
SubdivisionConfig bake_subdivision();

struct BakeConfig {
  SceneSource scene;
  SamplerConfig sampling;          ///< construction samples
  CostModel model;
  /// max_cells 0 (the default here): derived from the budget (4 x cells, or 4096 with memory).
  SubdivisionConfig subdivision = bake_subdivision();
  /// Weigh cells, draw AGVS's points and place cameras where players are (subdivision.play_space)
  /// whenever the scene's view space knows them (a Quake 3 map's leaves, or a mesh scene's
  /// walkable floors, viewspace/floor_space.h), unless subdivision.density or sampling.view_box
  /// says where viewers are: the command line's default, since a level's frames are seen from
  /// where players stand. The report gives what was decided and why (view_space_choice).
  bool play_space_where_known = true;
  /// Merge on AGVS's PVSs of the elementary cells (BuildConfig::merge_agvs; the validated
  /// merge): when merge_agvs is unset, resolve() makes it (seed: the construction samples' +
  /// 7000001, as many samples as the construction drew). False, with merge_agvs unset: greedy
  /// merging on the construction samples alone. A merge_agvs given is always used.
  bool merge_on_agvs = true;
  std::optional<AgvsConfig> merge_agvs;  ///< as BuildConfig::merge_agvs
  uint32_t cells = 0;              ///< budget: this many view cells ...
  uint64_t memory = 0;             ///< ... or a .pvs file of at most this many bytes
  /// The memory budget counts the compressed PVS lists alone (what stands against a map
  /// compiler's vis rows), not the whole file with point location and object names.
  bool memory_of_lists = false;
  /// Stopping rule (pixel error, time, samples), seed, batch. With no stop at all (none here,
  /// no measured_error, holes or max_seconds) resolve() stops at an estimated pixel error of 10.
  AgvsConfig agvs;
  /// The whole bake's time limit in seconds (0: none): each of the merge's two AGVS runs
  /// stops at a quarter of it; the proof at half of what the hierarchy left, nine tenths with
  /// `conservative`, whose sets are the proof's (cells not begun prove nothing); the PVSs' AGVS, with its measurements, at what is then left, less a quarter
  /// for each later stage of frame samples, near-object samples or measuring (down to a half,
  /// and at agvs.max_seconds); those stages, aimed rays included, at the limit itself, leaving
  /// out the frames and rays not begun by then (the report says how many frames were measured).
  /// The overshoot is one frame, one batch of rays and the file's writing. A hierarchy that
  /// leaves nothing is an Error (its --work copy is kept).
  double max_seconds = 0;
  /// Cameras that measure the PVSs as `viewcells measure` does (its placement, seed and
  /// frames: on a Quake 3 map player eyes above reachable floors); 0: none, unless resolve()
  /// decides (1,000 with holes, 5,000 with measured_error). The file written is measured, and
  /// its measured pixel error reported.
  uint32_t measure_cameras = 0;
  CameraConfig cameras;                      ///< placement and seed (count: measure_cameras)
  /// The measuring frames, as `measure`'s; width 0: resolve() decides (1024x768 with holes:
  /// what a player sees; else 64x48, the mean error estimator's cost).
  FrameConfig frame{0, 0, 90.0, 1024 * 1024};
  /// With measure_cameras: stop AGVS once the cameras' mean wrong pixels per 1024 x 1024
  /// frame are at most this (measured after one batch and at every doubling of the samples;
  /// the other limits still apply). Coarsening for a memory budget only unites PVSs, so the
  /// file written is measured again and never shows more. 0: not used.
  double measured_error = 0;
  /// With measure_cameras: also (or instead) stop once at most this share of the cameras' frames
  /// (0 to 1) shows any wrong pixel: the holes a player sees. 0: not used.
  double holes = 0;
  /// Frames as a sampler, after AGVS: this many cameras per view cell on average, placed as the
  /// measuring cameras are but from their own seed (never the measuring cameras: on a map,
  /// player eyes), each rendering `sample_frame`; every object a frame shows joins its cell's
  /// PVS. 0: none. Bounded by kMaxFrameRays, not by max_seconds.
  uint32_t frame_samples = 0;
  FrameConfig sample_frame{256, 192, 90.0, 1024 * 1024};
  /// Rounds of frame samples: after the first, only the cells whose last frames added an entry
  /// get about as many frames again (drawn from the same distribution, kept in those cells).
  uint32_t frame_rounds = 1;
  /// Near-object samples after AGVS (and the frame samples): each cell tests the neighbours of
  /// its PVS's objects with rays from `near_eyes` viewpoints a cell on average (placed as the
  /// measuring cameras are, from a seed of their own). rays_per_object 0: none.
  NearSampleConfig near;
  uint32_t near_eyes = 512;
  /// Prove objects hidden where the scene knows its solid space (a map's BSP, closed convex
  /// solids): every (view cell, object) pair is then proven visible (a ray saw it), proven
  /// hidden (no line from the cell reaches it through the portals) or undecided, and the report
  /// gives the classes and the cost of both bounds.
  bool prove_hidden = false;
  /// Ship the undecided pairs too: no line from any point of a cell reaches an object missing
  /// from its PVS (up to the proof's tolerance), at the conservative bound's cost. Error on a
  /// scene that can prove nothing hidden (every object would be in every PVS).
  bool conservative = false;
  /// Portals one flood may try before it keeps all it might reach. At 2M, on oa_dm5 (300 cells)
  /// 38 of 2,338 floods ran over it and the conservative cost was 0.79 of q3map2's (the proof:
  /// 672 s on 2 cores); at 200,000, 431 floods and 1.46 (docs/conservative.md).
  uint64_t hidden_max_steps = 2000000;
  /// With the proof, after the other samplers: rays aimed at each undecided (cell, object) pair,
  /// from uniform points of the cell's empty space to uniform points of the object's surface,
  /// up to this many a pair (in rounds of 8, 16, 32, ... while the pair stays undecided); an
  /// unblocked one proves the pair visible. The only pairs worth rays: the proof has decided
  /// the rest. 0: none.
  uint32_t aimed_rays = 0;
  std::string output;              ///< .pvs; empty: nothing written (the result is in BakeResult::file)
  std::string work_dir;            ///< empty: nothing kept between runs
  double checkpoint_seconds = 60;  ///< with a work directory: AGVS state saved this often (0: at the end)
};

struct BakeResult {
  BakeConfig config;
  std::vector<std::string> decided;  ///< what resolve() decided, in words
  uint64_t scene_fingerprint = 0;
  uint32_t object_count = 0;
  // The hierarchy.
  bool hierarchy_reused = false;
  uint32_t elementary_cells = 0;
  double hierarchy_seconds = 0;
  SamplingStats sampling;  ///< of the construction samples (zeros when reused)
  // The cut and the PVSs.
  uint32_t cells = 0;          ///< view cells in the file written
  uint32_t agvs_cells = 0;     ///< view cells AGVS sampled (more when the budget then coarsened them)
  std::string rule;
  AgvsStats agvs;
  double pixel_error = 0, pixel_error_bound = 0;  ///< NaN: not known
  std::optional<PixelErrorMeasure> measured;  ///< of the file written, by the measuring cameras
  std::string camera_rule;                    ///< how they were placed
  /// Which view space weighed the cells and placed the cameras, and why, in words.
  std::string view_space_choice;
  std::vector<MeasuredPoint> measured_curve;  ///< with measured_error: every measurement of the run
  bool measured_stop = false;                 ///< the measured error stopped AGVS
  bool agvs_resumed = false;
  // Frames as a sampler (frame_samples): cameras drawn, entries they added, seconds.
  uint64_t frame_sample_cameras = 0, frame_sample_entries = 0;
  double frame_sample_seconds = 0;
  NearSampleStats near;  ///< of the near-object samples
  uint64_t near_eyes = 0;
  double near_seconds = 0;
  std::string near_skipped;  ///< why the near-object samples did not run (no viewpoints), or empty
  /// The three answers per (view cell, object) pair, for the view cells AGVS sampled.
  struct HiddenClasses {
    bool proved = false;
    std::string method;                ///< what proved, or why nothing could be
    std::vector<std::string> warnings; ///< a leak, in words
    uint64_t visible = 0, hidden = 0, undecided = 0;  ///< pairs of rendered objects
    uint64_t conflicts = 0;  ///< pairs a ray saw that the proof calls hidden (a leak or a crack)
    /// Render cost per frame of the proven-visible sets (below exact visibility) and of the
    /// conservative sets (proven visible plus undecided: above it), weighed as `weights` says.
    double cost_visible = 0, cost_conservative = 0;
    std::string weights;
    uint64_t floods = 0, steps = 0, overflows = 0;
    uint64_t cells_unproven = 0;  ///< cells the time limit left unproven (all their pairs undecided)
    uint64_t aimed_pairs = 0, aimed_rays = 0, aimed_found = 0;  ///< aimed rays: pairs tried, rays, pairs seen
    double aimed_seconds = 0;
    double seconds = 0;
  } hidden;
  bool agvs_in_view_space = false;  ///< a Quake 3 map: AGVS drew its points in the non-solid space
  /// The view cells and PVSs baked, as written to `output` (point location, hierarchy,
  /// compressed lists and names): what read_pvs(output) gives, also when nothing was written.
  std::shared_ptr<const PvsFile> file;
  uint64_t pvs_entries = 0, file_bytes = 0;
  uint64_t list_bytes = 0;  ///< the visible sets of the file written as a compact handle holds them
  double mean_pvs = 0;
  double seconds = 0;
  int threads = 1;
};

/// What a bake decides from the rest of its config (every front end's bake goes through it, and
/// bake() calls it again: it changes nothing it has decided): the stop rule, the measuring
/// cameras and their frames, the merge's AGVS run. `decided` (when given) gets each decision in
/// words, for the report.
BakeConfig resolve(BakeConfig config, std::vector<std::string>* decided = nullptr);

/// Bakes: resolve(), then the chain. BakeResult::config is the config resolved, and
/// BakeResult::decided says what resolve() decided.
BakeResult bake(const BakeConfig& config, const Log& log);

/// The PVSs of the view cells `coarse` (MHT nodes of a cut at or above the cut `fine`): each
/// the union of the PVSs `fine_lists` of the fine cells below it. A viewpoint in a coarse cell
/// lies in one of its fine cells, so what any of them sees the coarse cell sees.
std::vector<std::vector<uint32_t>> coarsen(const MergeHistory& h, const std::vector<int32_t>& fine,
                                           const std::vector<std::vector<uint32_t>>& fine_lists,
                                           const std::vector<int32_t>& coarse);

}  // namespace viewcells::pipeline
