#pragma once
/// Adaptive global visibility sampling (AGVS; adaptive-global-visibility-sampling paper,
/// sections 4.1 to 4.5): the PVS of every view cell at once. Each visibility sample is a
/// maximal free segment (a forward and a backward ray); its objects go into every cell it
/// pierces, and its contribution c(s) (equation 2) is the number of PVS entries it adds. The
/// samples come from a mixture of distributions whose weights follow their contribution per
/// unit of cost, and the estimated pixel error (section 4.5) says when to stop.
///
/// Deterministic: work is done in batches; samples are drawn serially (Halton sequences for
/// the stationary distributions, seeded streams for the mutations; the silhouette searches
/// run in parallel from candidates and random numbers drawn serially), cast in parallel, and
/// their contributions applied in sample order. The cost unit of a distribution's weight is
/// the ray, not the second (the paper measures time): rays dominate the cost, and wall-clock
/// weights would make results depend on the machine and the thread count.
///
/// Also here: the visibility filter (section 5: PVSs extended by objects likely visible given
/// the sampling density) and dynamic edits (section 6: objects deleted and inserted, the
/// solution repaired, sampling resumed).
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "viewcells/bsp/subdivision.h"
#include "viewcells/cells/view_cells.h"
#include "viewcells/pvs/global_pvs.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// Adds a visibility sample's objects (kNoObject: none) to the PVS of every cell in `cells`
/// (those its segment pierces) and returns its contribution there, equation 2: the number of
/// new entries. contributed[e] tells whether end e's object added one, at_origin[e] whether
/// it added one to `origin_cell` (the ray from the sample's point towards end e was a wrong
/// pixel of a camera there: the pixel error estimator's contributing ray).
uint32_t contribute(GlobalPvs& pvs, const std::vector<int32_t>& cells, uint32_t object_a, uint32_t object_b,
                    bool contributed[2] = nullptr, int32_t origin_cell = -1, bool at_origin[2] = nullptr);

enum class AgvsMethod {
  kAgvs,  ///< the adaptive mixture of every distribution
  kSgvs,  ///< global, but the view space-direction distribution alone (stationary)
  kRef,   ///< per cell: a random cell, a random ray from a random point in it, for that cell only
};
/// Parses "agvs", "sgvs", "ref" (Error otherwise).
AgvsMethod parse_agvs_method(const std::string& name);
const char* to_string(AgvsMethod m);

enum class AgvsDistribution : int {
  kViewSpaceDirection = 0,  ///< uniform point in view space, uniform direction
  kObjectDirection,         ///< point on an object, cosine-weighted direction about its normal
  kTwoPoint,                ///< from a point in view space towards a point on an object
  kTwoPointMutation,        ///< both ends of a contributing segment moved by Gaussians
  kSilhouetteMutation,      ///< towards the silhouette of a newly seen object, and past a depth jump
  kCount
};
const char* to_string(AgvsDistribution d);

struct AgvsConfig {
  AgvsMethod method = AgvsMethod::kAgvs;
  uint64_t seed = 1;
  uint32_t batch_size = 20000;  ///< samples per batch: the window of the mixture's weights
  // Termination: the first criterion met (0: not used; at least one must be set). Counted
  // from the start of the computation, a resumed state included, and checked between batches
  // (a run may pass max_samples by less than a batch).
  uint64_t max_samples = 0;
  double max_seconds = 0;
  double pixel_error = 0;           ///< stop when the estimated pixel error is at most this
  uint32_t resolution = 1024 * 1024;  ///< pixels of the estimator's camera image
  double window_p = 0.9, window_k = 0.5;  ///< equation 5
  /// Batches drawn from every distribution in equal shares (calibration passes): the first
  /// one, then one every `recalibrate_every` samples.
  uint64_t recalibrate_every = 2'000'000;
  uint32_t mutation_buffer = 1 << 18;  ///< mutation candidates kept (fewest mutations first)
  /// The mutations' lanes: each holds its own candidates (mutation_buffer / lanes of them),
  /// draws its share of every batch's mutation samples from its own random stream, and is fed
  /// the candidates of the samples whose index in the batch is its number modulo the lanes.
  /// Lanes draw and take candidates independently: in parallel on a machine's cores and, on
  /// a cluster, each on its own rank. 1 keeps one buffer and one stream, as the paper does.
  /// The result depends on it (as on the seed), never on the threads or ranks.
  uint32_t mutation_lanes = 1;
  /// Share of each batch kept for the view space-direction distribution whatever its
  /// weight: the pixel error estimator needs its rays (at 5%, AGVS's estimator could not
  /// resolve errors below several pixels), and it guarantees progress everywhere.
  double min_share = 0.25;
  EmptySpaceMode empty_space = EmptySpaceMode::kAuto;
  /// Where a viewer can stand (a Quake 3 map's non-solid space); empty: the whole view box.
  /// The view space-direction and two-point samples' points, and REF's, are drawn there (Halton
  /// points outside are skipped), so no samples are spent in solid space and the pixel error
  /// estimator's cameras stand where viewers do.
  std::function<bool(const Vec3&)> view_space;
  /// Where those points come from: a map of the unit cube's (Halton) points to points of the
  /// view space, uniform over it where it returns a point; a point with a NaN coordinate is
  /// skipped like one outside view_space. Empty: the view box, scaled. A view space that fills
  /// little of its box (a map's play space) is drawn this way at the cost of the points it
  /// skips rather than of all the box's.
  std::function<Vec3(double, double, double)> view_point_map;
  /// Keep the visibility filter's sampling densities (segments per cell; per cell and object,
  /// those that hit it: 2 bytes per cell and object). Required by the object space filter.
  bool filter_statistics = false;
  bool show_progress = true;
};

/// The visibility filter (paper section 5), applied to a copy of the PVSs (sampling goes on
/// with the unfiltered ones). Object space: each object o of a cell's PVS has its bounding box
/// extended by e(o) = k min(e_g(o), e_l(o)), e_g = 2 d(o) / sqrt(n_v) (d: distance between the
/// cell's and the object's bounds, n_v: segments through the cell), e_l = r(o) / sqrt(n_v(o))
/// (r: half the object's diagonal, n_v(o): segments through the cell that hit o), and every
/// rendered object its box touches joins the PVS. View space: each cell's PVS is merged with
/// those of its `view_neighbours` neighbouring cells with the most similar PVSs (Jaccard).
struct VisibilityFilter {
  bool object_space = true;
  double k = 1.0;
  uint32_t view_neighbours = 0;
};

/// What a dynamic edit did.
struct AgvsEditStats {
  uint32_t deleted = 0, inserted = 0;
  uint64_t removed_deleted = 0;   ///< entries of deleted objects
  uint64_t removed_penumbra = 0;  ///< entries in an inserted object's penumbra from their cell
  uint32_t cells_cleared = 0;     ///< cells an inserted object touches (their PVS emptied)
};

/// Objects of `before` that are still in `after`, by name and identical geometry (in order
/// among equals): new_of_old[o] is o's index in `after`, or kNoObject when it was deleted (or
/// changed: an edit is a deletion and an insertion). Objects of `after` that no entry names
/// are the inserted ones.
std::vector<uint32_t> match_objects(const Scene& before, const Scene& after);

/// One point of the convergence curve, after a batch.
struct AgvsPoint {
  double seconds = 0;
  uint64_t samples = 0, rays = 0;
  double mean_pvs = 0;     ///< mean PVS size over the cells
  double pixel_error = 0;  ///< estimated (NaN before the first window is full)
  double pixel_error_bound = 0;  ///< see AgvsSolver::pixel_error_bound (NaN when none)
  uint64_t camera_rays = 0, wrong_camera_rays = 0;  ///< the estimator's rays so far, in all
  static constexpr int kReferences = 2;
  /// Entries also in reference PVS k (AgvsSolver::add_reference; 0 without one): how much of
  /// another method's solution this one has found.
  uint64_t covered[kReferences] = {};
};

struct AgvsStats {
  uint64_t samples = 0, rays = 0, batches = 0;
  static constexpr int kDistributions = static_cast<int>(AgvsDistribution::kCount);
  uint64_t dist_samples[kDistributions] = {};
  uint64_t dist_rays[kDistributions] = {};  ///< silhouette: its discovery rays included
  uint64_t dist_contribution[kDistributions] = {};
  double dist_probability[kDistributions] = {};  ///< of the last batch
  uint64_t mutation_candidates = 0;           ///< in the buffer now
  /// Camera rays in the estimator's window (equation 5), or those the bound was computed over.
  uint64_t window_rays = 0;
  uint64_t camera_rays = 0, wrong_camera_rays = 0;  ///< the estimator's rays since the start
  double seconds = 0;
  /// Where this run's time went, batch by batch (not saved with the state), in four parts that
  /// add up: planning the batch (the mixture's shares and the stationary distributions' Halton
  /// index ranges; REF's draws), the mutation lanes (drawing their samples, silhouette searches
  /// included, and taking their candidates: divided among threads and, on a cluster, ranks),
  /// drawing the stationary distributions' samples, casting them and finding the cells (chunk by
  /// chunk, each drawn and cast by one rank; the exchange of results included), and applying the
  /// segments to the table (divided by cells).
  double draw_seconds = 0, cast_seconds = 0, apply_seconds = 0, mutation_seconds = 0;
  uint64_t segments = 0, pierced_cells = 0;  ///< segments applied, and cells they pierced in all
  std::string stop_reason;
  EmptySpaceDecision empty_space;
  std::vector<AgvsPoint> curve;
};

/// The global visibility solver. Construct, then run(); run() again resumes with more budget.
class AgvsSolver {
 public:
  /// The scene, caster and cells must outlive the solver.
  AgvsSolver(const Scene& scene, const RayCaster& caster, const CellLocator& cells, const AgvsConfig& config);
  ~AgvsSolver();
  /// Samples batch by batch until a termination criterion of the config holds.
  void run();
  /// Sets new termination criteria (totals, as in AgvsConfig; for resuming).
  void set_limits(uint64_t max_samples, double max_seconds, double pixel_error);
  /// Between batches, when at least `seconds` have passed since the run started or the last
  /// call, run() calls `save` (a checkpoint: typically save() to a file). What it sees is the
  /// state an interrupted run resumes from; it must not change the solver.
  void set_checkpoint(double seconds, std::function<void()> save);
  /// Writes the whole state (PVSs, sampling and mixture state, statistics) to a versioned,
  /// checksummed file; `identity` names the scene and view cells it belongs to.
  void save(const std::string& path, uint64_t identity) const;
  /// Restores a state written by save() for the same scene, cells (identity) and method and
  /// seed; sampling then continues exactly as if it had not stopped. Error on any mismatch or
  /// corruption, and then the solver is unchanged.
  void load(const std::string& path, uint64_t identity);
  /// A reference solution (e.g. another method's final PVSs, same cells and objects): every
  /// point of the convergence curve counts the entries it shares with it. At most
  /// AgvsPoint::kReferences; Error when the shape differs.
  void add_reference(GlobalPvs reference);
  /// The identity a state file was saved with (Error when it is not a readable state).
  static uint64_t state_identity(const std::string& path);
  const GlobalPvs& pvs() const;
  const AgvsStats& stats() const;
  /// Dynamic edits (paper section 6): the scene becomes `edited` (with its caster; both must
  /// outlive the solver), whose objects are the old ones through `new_of_old` (kNoObject:
  /// deleted) plus the inserted ones. Deleted objects leave every PVS; for each inserted
  /// object and each cell, the PVS entries whose bounds meet the object's penumbra from the
  /// cell (ConvexRegion, by CGAL's hull) are removed, since it may now hide them. The
  /// estimator's window restarts; run() then resumes sampling, which finds again what is
  /// still visible. Error (solver unchanged) when the map is not one-to-one or the edited
  /// scene cannot be sampled.
  AgvsEditStats edit(const Scene& edited, const RayCaster& caster, const std::vector<uint32_t>& new_of_old);
  /// The PVSs with the visibility filter applied (sorted object lists per cell). Error when
  /// the object space filter is asked for without config.filter_statistics.
  std::vector<std::vector<uint32_t>> filtered_pvs(const VisibilityFilter& filter) const;
  /// The current pixel error estimate (section 4.5): wrong camera rays, i.e. view
  /// space-direction rays from free space that added an entry to the cell of their origin,
  /// per ray of the window, times the resolution. NaN before the first full window.
  double pixel_error() const;
  /// The window reaches back over the newer half of all camera rays at most (the estimate
  /// describes the current solution). When even that half holds too few wrong rays for
  /// equation 5, there is no estimate, and this is the one-sided 90% upper bound of the error
  /// over it (Poisson); NaN otherwise. Termination by pixel error accepts it.
  double pixel_error_bound() const;
  double mean_pvs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The PVS of every leaf of `s` by AGVS (config's sampling and stopping rule), per node of `s`
/// (empty for inner nodes; bsp/subdivision.h's leaf_pvs has the same shape), each united with
/// `base` (per node too; empty: none), typically the construction samples' leaf PVSs. What
/// merging decides on when the construction samples are too few per leaf.
struct LeafPvsRun {
  std::vector<std::vector<uint32_t>> pvs;
  AgvsStats stats;
};
LeafPvsRun leaf_pvs_by_agvs(const Scene& scene, const RayCaster& caster, const Subdivision& s,
                            const AgvsConfig& config, const std::vector<std::vector<uint32_t>>& base = {});

}  // namespace viewcells
