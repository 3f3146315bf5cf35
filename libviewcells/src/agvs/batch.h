#pragma once
// AGVS paper 4.1: what one batch of global visibility sampling holds between its steps, drawn
// (batch_draw.cpp), cast (batch_cast.cpp) and applied (batch.cpp). Internal to the solver.
#include <cstdint>
#include <limits>
#include <vector>

#include "solver_impl.h"

namespace viewcells {

/// The view space-direction samples last: they also replace the mutations' draws that failed (no
/// mutation candidate left, a degenerate two-point pair), so every batch has about n samples
/// (the stationary distributions' chunks are index ranges sized from the share of the view
/// space's points so far).
inline constexpr int kOrder[kDists] = {kSil, kTpm, kOd, kTp, kVsd};

/// Samples a casting chunk holds at most (a mutation's or REF's), and on average (a stationary
/// distribution's, whose chunks are Halton index ranges).
inline constexpr uint32_t kChunkSamples = 1024;

/// A batch's samples, grouped by distribution so that each distribution's rays are counted
/// exactly: samples first_of[d] .. end_of[d] - 1 are distribution d's.
struct AgvsSolver::Impl::BatchSamples {
  /// The mutations' samples (only a lane's owner knows their points) and REF's. The stationary
  /// distributions' samples are drawn by the rank that casts them, chunk by chunk, and never
  /// gathered here.
  std::vector<Vec3> points, dirs;
  std::vector<int32_t> ref_cell;  ///< REF: the cell each sample belongs to
  /// The stationary distributions' chunks, in kOrder: a range of Halton indices each, whose
  /// points outside the view space (and degenerate samples) are skipped, so that a chunk's
  /// samples do not depend on any other chunk's (AgvsSolver::Impl::draw_stationary).
  struct HaltonRange {
    int dist;
    uint64_t first;
    uint32_t count;
  };
  std::vector<HaltonRange> stationary;
  uint32_t count = 0;  ///< all samples of the batch, known once every chunk is cast
  /// The mutation samples' runs by lane: distribution, lane, first sample, count. Only the
  /// lane's owner (a rank) knows their points.
  struct LaneRange {
    int dist;
    uint32_t lane, first, size;
  };
  std::vector<LaneRange> lane_ranges;
  uint32_t first_of[kDists] = {}, end_of[kDists] = {};
  uint64_t discovery_rays = 0;  ///< the silhouette searches' rays
};

/// Segments cast from a fixed run of one distribution's samples.
struct AgvsSolver::Impl::BatchChunk {
  uint32_t first = 0, size = 0;
  int dist = 0;
  int32_t lane = -1;  ///< the first mutation lane whose samples these are (-1: a stationary distribution's)
  /// A stationary distribution's chunk: the Halton indices its caster draws (count 0: the
  /// samples first .. first + size - 1 of BatchSamples).
  uint64_t halton_first = 0;
  uint32_t halton_count = 0;
  SegmentSet segs;
  std::vector<uint32_t> sample_of;
  /// Every (segment, cell) with the segment having length in the cell, in segment order (not for
  /// REF); on several ranks only those of this rank's cells (cell mod ranks == rank).
  struct CellPair {
    uint32_t segment;  ///< index in the chunk
    int32_t cell;
  };
  std::vector<CellPair> pairs;
  /// View space-direction chunks: per segment, the cell of its sample's point when it is that
  /// sample's camera segment (the first of its segments through the point: the estimator's
  /// camera sees along both its rays), else kNotCamera. Found by the caster, the only rank that
  /// knows the points.
  static constexpr int32_t kNotCamera = std::numeric_limits<int32_t>::min();
  std::vector<int32_t> camera_cell;
  /// On several ranks (not REF): the pairs of this rank's cells, routed to it by the chunk's
  /// caster with what inserting needs of their segment (pairs is then empty).
  struct RoutedPair {
    uint32_t segment;  ///< index in the chunk
    int32_t cell;
    uint32_t objects[2];
    int32_t camera_cell;  ///< as camera_cell (kNotCamera: not its sample's camera segment)
  };
  std::vector<RoutedPair> routed;
  /// Whether this rank cast the chunk and holds its segments: always in one process and for
  /// REF; on several ranks otherwise only its caster, and the others know its counts alone.
  bool here = true;
  uint32_t segment_count = 0;  ///< its segments, known on every rank
  uint64_t pierced = 0;  ///< all ranks' pairs
  uint64_t rays = 0;
  size_t seg_start = 0;  ///< index of its first segment among the batch's
};


/// Lane l's share of n draws.
inline uint32_t lane_share(uint32_t n, size_t lanes, size_t l) {
  return static_cast<uint32_t>(n / lanes + (l < n % lanes ? 1 : 0));
}
/// Lane l's random stream in batch `index`: lane 0's is the batch's own (one lane draws as the
/// single buffer did).
inline uint64_t lane_stream(uint64_t index, size_t l) { return 1000 + index + (static_cast<uint64_t>(l) << 40); }

}  // namespace viewcells
