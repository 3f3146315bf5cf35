#pragma once
/// `viewcells pvs`: the view cells' PVSs by adaptive global visibility sampling (AGVS, or its
/// SGVS and REF variants), optionally continued from a saved state, across a dynamic edit of
/// the scene, filtered, measured by cameras; written compressed as .pvs.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/agvs/agvs.h"
#include "viewcells/eval/frames.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pipeline/measure.h"

namespace viewcells::pipeline {

struct PvsConfig {
  std::string hierarchy_path;
  std::string scene_path;
  ObjectGrouping grouping = ObjectGrouping::kAuto;
  bool robust = true;
  uint32_t cells = 0;  ///< view cells cut from the history; 0: every elementary cell
  AgvsConfig agvs;     ///< method, seed, batch, stopping rule; filter_statistics is derived
  VisibilityFilter filter;
  bool filter_object_space = false;
  uint32_t measure_cameras = 0;
  uint32_t measure_size = 1024;
  /// With measure_cameras: also measure the PVSs (unfiltered) after these many samples
  /// (ascending; those beyond the stopping rule are not reached), with the same cameras. The
  /// solver's clock does not run while measuring.
  std::vector<uint64_t> measure_at;
  /// With measure_cameras: a stopping rule by measured error. The PVSs are measured after one
  /// batch, then at every doubling of the samples, and sampling stops at the first measurement
  /// whose cameras show at most this many wrong pixels on average (scaled to the estimator's
  /// resolution, 1024 x 1024 by default: the paper's pixel error, measured instead of estimated),
  /// or when another limit is reached first. 0: not used.
  double measured_error = 0;
  std::string save, resume, edited_from;
  double save_every = 0;  ///< with `save`: also write the state every this many seconds (a checkpoint)
  std::vector<std::string> references;
  std::string output;
};

/// The identity a saved AGVS state carries: the scene's fingerprint and the view cells.
uint64_t pvs_state_identity(uint64_t scene_fingerprint, const PvsFile& cells);

/// The PVSs measured by cameras part-way through the run.
struct MeasuredPoint {
  uint64_t samples = 0, rays = 0;
  double seconds = 0;          ///< the solver's own time so far (measuring excluded)
  double mean_pvs = 0;
  double estimated = 0;        ///< the estimator's pixel error then (NaN: none)
  PixelErrorMeasure measured;  ///< `wrong` left empty
  /// Seconds of sampling still needed for the target, from a power law through this and the
  /// previous measurement (NaN: not known yet, or the error did not fall; 0: met).
  double eta_seconds = 0;
};

/// What measured frames must show for AGVS to stop; 0 leaves a part out, and every part given
/// must hold: the mean wrong pixels per frame (scaled to the frame's resolution, 1024 x 1024),
/// and the share of frames with any wrong pixel (0 to 1: the holes a player sees).
struct MeasuredTarget {
  double mean = 0;
  double holes = 0;
  bool any() const { return mean > 0 || holes > 0; }
  bool met(const PixelErrorMeasure& m) const;
  /// E.g. "at most 1.00% of frames with a wrong pixel and a mean of at most 1.000 wrong pixels".
  std::string describe() const;
};

/// Where one rank's AGVS time went (AgvsStats' phases, and its waiting in collectives).
struct RankPhases {
  double draw_seconds = 0, mutation_seconds = 0, cast_seconds = 0, apply_seconds = 0, exchange_seconds = 0;
};

/// Every rank's phases, in rank order, on every rank (one entry in one process). Collective.
std::vector<RankPhases> gather_phases(const AgvsStats& stats);

struct PvsResult {
  PvsConfig config;
  std::string rule;
  uint32_t cells = 0;
  AgvsStats stats;
  std::vector<RankPhases> rank_phases;  ///< where each rank's time went
  AgvsConfig agvs;  ///< as run (resolution, window, filter statistics)
  bool filtering = false;
  double mean_pvs = 0, mean_written = 0;
  uint64_t pvs_entries = 0;
  double pixel_error = 0, pixel_error_bound = 0;  ///< NaN: not known
  double setup_seconds = 0;
  int threads = 1;
  std::optional<PixelErrorMeasure> measured, measured_unfiltered;
  std::string camera_rule;               ///< how the measuring cameras were placed
  std::vector<MeasuredPoint> measured_curve;
  std::optional<AgvsEditStats> edit;
};

PvsResult compute_pvs(const PvsConfig& config, const Log& log);

}  // namespace viewcells::pipeline
