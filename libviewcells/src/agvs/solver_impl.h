#pragma once
#include <functional>
// AGVS paper 4.6 (putting it all together): the solver's state, shared by the files that
// implement its parts: distributions.cpp (4.3, 4.4), mixture.cpp (4.2), batch.cpp (4.1, one
// batch of the sampling loop), estimator.cpp (4.5), filter.cpp (5), edit.cpp (6),
// state_io.cpp (saving and resuming) and agvs.cpp (the loop and the public API).
#include <algorithm>
#include <array>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include "box_tree.h"
#include "candidates.h"
#include "halton.h"
#include "viewcells/agvs/agvs.h"
#include "viewcells/core/ranks.h"
#include "viewcells/core/error.h"
#include "viewcells/core/rng.h"
#include "viewcells/sampling/sampler.h"

namespace viewcells {

namespace agvs_detail {
constexpr int kDists = static_cast<int>(AgvsDistribution::kCount);
constexpr int kVsd = 0, kOd = 1, kTp = 2, kTpm = 3, kSil = 4;
constexpr uint32_t kMaxMutationLanes = 1 << 16;

/// One lane of the mutation strategies (AgvsConfig::mutation_lanes): its candidates for both
/// mutations. On several ranks, a lane is drawn and fed by its owner only (Impl::lane_owner;
/// the others' copies are stale until sync()); its candidate count is kept current on every
/// rank (both buffers always hold the same number: add() adds to both, take() moves one).
struct MutationLane {
  CandidateBuffer two_point, silhouette;
  uint64_t count = 0;
};

/// contribute() in one cell: inserts the objects (skipping none, and b when it is a) with
/// insert(object) -> bool (new), returns the entries added, and marks contributed[e] and,
/// when the cell is the sample's origin cell, at_origin[e].
template <class Insert>
uint32_t contribute_in_cell(Insert&& insert, const uint32_t objs[2], bool origin, bool contributed[2],
                            bool at_origin[2]) {
  uint32_t gain = 0;
  for (int e = 0; e < 2; ++e) {
    if (objs[e] == kNoObject || (e == 1 && objs[1] == objs[0])) continue;
    if (!insert(objs[e])) continue;
    ++gain;
    if (contributed) contributed[e] = true;
    if (at_origin && origin) at_origin[e] = true;
  }
  return gain;
}
}  // namespace agvs_detail

using namespace agvs_detail;

struct AgvsSolver::Impl {
  const Scene* scene_;  ///< rebound by scene edits
  const CellLocator& cells;
  AgvsConfig config;
  const RayCaster* caster_ref_;
  std::unique_ptr<SegmentCaster> caster_;
  GlobalPvs pvs;
  AgvsStats stats;
  double checkpoint_every = 0;          ///< seconds between checkpoints (0: none)
  std::function<void()> checkpoint;     ///< called between batches, at most every checkpoint_every
  // Surface sampling: rendered objects, and each one's triangles by cumulative area.
  std::vector<uint32_t> objects;
  std::vector<std::vector<std::pair<double, uint32_t>>> triangles_of;
  std::vector<double> object_radius;
  Halton halton[kDists];
  uint64_t halton_index[kDists] = {};
  // Mutation candidates of the two mutation strategies, in lanes.
  std::vector<MutationLane> lanes;
  size_t lane_capacity = 0;  ///< candidates a lane keeps
  // The mixture: contribution and rays of each distribution in the last batch.
  double weight[kDists] = {};
  double recent_contribution[kDists] = {}, recent_rays[kDists] = {};
  uint64_t last_calibration = 0;
  bool calibrated = false;
  // The pixel error estimator's window: per batch, view space-direction rays and those that
  // added an entry to the cell containing their origin.
  std::deque<std::pair<uint64_t, uint64_t>> window;
  uint64_t window_total = 0;  ///< camera rays since the start (or the last edit), trimmed ones too
  double error = std::numeric_limits<double>::quiet_NaN();
  /// With too few wrong camera rays for a window: the error's 90% upper bound, in pixels.
  double error_bound = std::numeric_limits<double>::quiet_NaN();
  double eps;  ///< offset of ray origins from surfaces
  // The visibility filter's sampling densities (config.filter_statistics): segments through
  // each cell, and per cell and object the segments through the cell that hit the object
  // (saturating).
  std::vector<uint64_t> cell_samples;
  std::vector<uint16_t> hit_counts;
  std::vector<GlobalPvs> references;  ///< for the curve's coverage only
  // On several ranks (core/ranks.h) the cells are partitioned: rank r applies segments to
  // the cells c with c mod ranks == r, so each rank's table is current in its own rows only
  // (`partitioned` is then true) until sync() combines them. Everything else is the same on
  // every rank: a segment's gain is summed and its flags or-ed over the ranks before they are
  // used, in sample order.
  bool partitioned = false;
  uint64_t synced_entries = 0;  ///< entries of the table at the last sync()
  uint64_t global_entries = 0;  ///< entries of all ranks' rows together (while partitioned)

  const Scene& scene() const { return *scene_; }
  const RayCaster& caster_ref() const { return *caster_ref_; }
  const SegmentCaster& caster() const { return *caster_; }

  Impl(const Scene& s, const RayCaster& rc, const CellLocator& c, const AgvsConfig& cfg)
      : cells(c),
        config(cfg),
        pvs(c.cell_count(), static_cast<uint32_t>(s.object_count())),
        halton{Halton(cfg.seed, 11), Halton(cfg.seed, 12), Halton(cfg.seed, 13), Halton(cfg.seed, 14),
               Halton(cfg.seed, 15)} {
    bind(s, rc);
    lanes.resize(config.mutation_lanes);
    lane_capacity = config.mutation_buffer / config.mutation_lanes;
    if (config.filter_statistics) {
      cell_samples.assign(c.cell_count(), 0);
      hit_counts.assign(size_t(c.cell_count()) * s.object_count(), 0);
    }
  }

  /// Takes the scene and its caster: what sampling derives from them.
  void bind(const Scene& s, const RayCaster& rc);

  /// A point on a random rendered object from Halton coordinates (u0 object, u1 triangle,
  /// u2, u3 barycentric) and the triangle's unit normal.
  Vec3 object_point(double u0, double u1, double u2, double u3, Vec3& normal) const;

  Vec3 view_point(double u0, double u1, double u2) const {
    if (config.view_point_map) return config.view_point_map(u0, u1, u2);
    const Box3& b = cells.view_box();
    const Vec3 e = b.extent();
    return {b.lo.x + e.x * u0, b.lo.y + e.y * u1, b.lo.z + e.z * u2};
  }

  /// Sample `i` of a stationary distribution d (view space-direction, object-direction,
  /// two-point) into (point, dir), `at` its view point (unused for object-direction); false
  /// when degenerate. Thread-safe.
  bool stationary_sample(int d, uint64_t i, const Vec3& at, Vec3& point, Vec3& dir) const;
  /// The samples of stationary distribution d at Halton indices first .. first + count - 1,
  /// appended in order: an index whose view point lies outside the view space, or whose sample
  /// is degenerate, gives none. Depends on nothing else, so a chunk's caster draws it alone.
  /// Thread-safe.
  void draw_stationary(int d, uint64_t first, uint32_t count, std::vector<Vec3>& points, std::vector<Vec3>& dirs) const;
  /// The expected share of distribution d's Halton indices that give a sample: 1 without a
  /// view space (or for object-direction); else from the samples and indices so far, and before
  /// the first 4,096 indices from a test of those (computed once, the same on every rank).
  double sample_share(int d);
  double pilot_share[kDists] = {-1, -1, -1, -1, -1};
  /// Draws one two-point mutation sample from `lane` into (point, dir); false when it cannot
  /// (no candidate, a degenerate pair).
  bool draw_two_point_mutation(Rng& rng, MutationLane& lane, Vec3& point, Vec3& dir);

  /// Lanes form at most kLaneGroups groups of consecutive lanes: a group's mutation samples are
  /// cast in chunks of their own (chunk boundaries order a chunk's segments, so they must not
  /// depend on the ranks), and groups are dealt to the ranks in turn.
  static constexpr size_t kLaneGroups = 64;
  size_t lane_group(size_t l) const { return l * kLaneGroups / lanes.size(); }
  /// The rank that draws and feeds mutation lane l.
  int lane_owner(size_t l) const { return static_cast<int>(lane_group(l) % static_cast<size_t>(ranks::size())); }
  bool my_lane(size_t l) const { return lane_owner(l) == ranks::rank(); }
  uint64_t mutation_candidates() const {
    uint64_t n = 0;
    for (const MutationLane& l : lanes) n += l.count;
    return n;
  }
  /// Where mutation candidates' ends may lie: the view box and the scene, with slack for rounding.
  Box3 candidate_bounds() const;
  void save_lane(ByteWriter& w, const MutationLane& lane) const {
    lane.two_point.save(w);
    lane.silhouette.save(w);
  }
  /// A lane as save_lane() wrote it; fails on `r` (a corrupt file) where a candidate cannot be.
  MutationLane load_lane(ByteReader& r, size_t payload) const;

  /// Silhouette mutation (paper 4.4, after Wonka et al.'s adaptive border sampling): from the
  /// candidate's other end, discovery rays towards points moved off the seen object along a
  /// random direction of the plane through its end, perpendicular to the segment; the nearest
  /// one that misses the object (binary search) passes its silhouette. If that ray then hits
  /// something more than k r(o) beyond the moved point (a depth discontinuity), a second
  /// search runs along the jump. Returns the samples' points and directions (one or two).
  /// `angle_u`: the two uniform numbers that choose the directions of the two searches (drawn
  /// beforehand, so that searches run in parallel and stay reproducible); `rays` counts the
  /// discovery rays. Thread-safe.
  int silhouette_samples(const Candidate& c, const double angle_u[2], Vec3 points_out[2], Vec3 dirs_out[2],
                         uint64_t& rays) const;

  /// The filter's densities: one more segment through `cell`, hitting objects a and b.
  void count_hits(int32_t cell, uint32_t a, uint32_t b) {
    ++cell_samples[cell];
    const size_t row = size_t(cell) * pvs.object_count();
    auto bump = [&](uint32_t o) {
      if (o == kNoObject) return;
      uint16_t& h = hit_counts[row + o];
      if (h < std::numeric_limits<uint16_t>::max()) ++h;
    };
    bump(a);
    if (b != a) bump(b);
  }

  /// Radius of what lies at a segment end: its object, or else the view cell there.
  double end_radius(uint32_t object, const Vec3& p) const {
    if (object != kNoObject) return object_radius[object];
    const int32_t c = cells.cell_at(p);
    return c >= 0 ? 0.5 * cells.cell_bounds(c).diagonal() : 0.0;
  }

  /// The shares of the next batch's samples.
  void shares(double share[kDists]);

  void batch(uint64_t index, uint32_t n);
  // The stages of a batch (batch.cpp).
  struct BatchSamples;
  struct BatchChunk;
  struct BatchCounts;
  void draw_samples(uint64_t index, uint32_t n, const double share[kDists], BatchSamples& s);
  /// The batch's mutation samples (want[kSil], want[kTpm]), lane by lane, each lane from its
  /// own stream; on several ranks each rank draws its own lanes and the others' are only
  /// counted. Returns the draws that failed.
  uint32_t draw_mutations(uint64_t index, const uint32_t want[kDists], BatchSamples& s);
  /// Feeds each lane the candidates of its contributing segments, in sample order.
  void add_candidates(const std::vector<BatchChunk>& chunks, const std::vector<uint32_t>& gains,
                      const std::vector<uint8_t>& flags, const std::vector<std::array<double, 2>>& radius);
  /// REF's casting as the paper describes it: one forward ray per sample, into chunk `c`.
  void cast_ref_chunk(const BatchSamples& s, BatchChunk& c) const;
  /// Draws the stationary distributions' chunks and casts every chunk (on several ranks, each its
  /// own, then shared); numbers the stationary samples (s.first_of, s.end_of, s.count).
  std::vector<BatchChunk> cast_samples(BatchSamples& s);
  /// Applies a batch's segments in sample order: the table (on several ranks, each rank's own
  /// cells, then the gains and flags reduced over the ranks), then the counts and mutation
  /// candidates that follow from them.
  void apply_segments(const BatchSamples& s, const std::vector<BatchChunk>& chunks, BatchCounts& counts);
  /// Pass 1 of apply_segments for every method but REF: each segment's objects into the table
  /// of every cell it pierces (this rank's), in sample order per cell, in parallel over cells;
  /// its gains (entries added) and flags (contributed a, b; at origin a, b), and whether it is
  /// its sample's camera segment (BatchChunk::camera_cell), which the estimator counts. Its
  /// pairs are the chunks' own (one process) or those routed to this rank.
  void insert_segments(const std::vector<BatchChunk>& chunks, std::vector<uint32_t>& gains,
                       std::vector<uint8_t>& flags);
  /// Several ranks, REF: each rank casts its chunks, and every rank receives all of them.
  void gather_chunks(std::vector<BatchChunk>& chunks, const std::function<void(BatchChunk&)>& cast_chunk);
  /// Several ranks: the rank that casts chunk k (the same function on every rank).
  int chunk_owner(const std::vector<BatchChunk>& chunks, size_t k) const;
  /// Several ranks (not REF): each rank draws and casts its chunks, every rank learns every
  /// chunk's counts, and each (segment, cell) pair goes only to its cell's rank.
  void route_chunks(std::vector<BatchChunk>& chunks, const std::function<void(BatchChunk&)>& cast_chunk);
  /// Several ranks (not REF): each segment's gains and flags from the ranks of its cells to its
  /// caster, summed and or-ed there.
  void return_outcomes(const std::vector<BatchChunk>& chunks, std::vector<uint32_t>& gains,
                       std::vector<uint8_t>& flags);
  /// Several ranks (not REF): the casters send each contributing end's candidate to its lane's
  /// owner, which feeds its lanes in sample order; every rank learns the lanes' counts.
  void route_candidates(const std::vector<BatchChunk>& chunks, const std::vector<uint8_t>& flags,
                        const std::vector<std::array<double, 2>>& radius);
  /// Combines the ranks' rows (and the filter's densities): afterwards every rank holds the
  /// whole table. Collective. No-op in one process.
  void sync();
  /// The mixture's weights after a batch (mixture.cpp), and the per-distribution statistics.
  void update_weights(const double share[kDists], const uint64_t samples[kDists], const uint64_t contribution[kDists],
                      const uint64_t rays[kDists]);

  /// Equation 5: the window holds the most recent batches whose camera rays (view
  /// space-direction rays from free space) number at least (1 - e) / (k^2 e (1 - P)), e the
  /// wrong share over them.
  void update_estimate(uint64_t rays, uint64_t wrong);

  /// The window reaches back at most over the newer half of all camera rays so far: an
  /// estimate must describe the current solution, and the error keeps falling. If even that
  /// half holds too few wrong rays for equation 5 (the error is below what it resolves), there
  /// is no estimate, and error_bound gives the one-sided 90% Poisson upper bound over it.
  void evaluate_window();

  double mean_pvs() const {
    return static_cast<double>(partitioned ? global_entries : pvs.entries()) / cells.cell_count();
  }

  AgvsEditStats edit(const Scene& edited, const RayCaster& rc, const std::vector<uint32_t>& new_of_old);

  std::vector<std::vector<uint32_t>> filtered(const VisibilityFilter& f) const;
};

}  // namespace viewcells
