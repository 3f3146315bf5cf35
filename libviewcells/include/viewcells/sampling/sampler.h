#pragma once
/// Visibility segment sampling (view-cell-construction paper, section 4.1): points uniform in
/// the view space box, directions uniform on the sphere, a forward and a backward ray, the
/// segment between their termination points. Objects one sees through do not stop the rays;
/// each one a segment crosses gets a segment of its own along the same line. Parallel and reproducible: samples are drawn in
/// fixed-size batches, each with its own random stream, so the output is bit-identical for
/// any number of threads.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/segments.h"

namespace viewcells {

enum class EmptySpaceMode { kAuto, kOn, kOff };
/// Parses "auto", "on", "off"; throws Error otherwise.
EmptySpaceMode parse_empty_space_mode(const std::string& s);

struct SamplerConfig {
  uint64_t samples = 1'000'000;  ///< samples drawn; the valid ones become segments
  /// If > 0: draw samples until this many segments exist (then `samples` is ignored); the
  /// output is the first target_segments segments in batch order.
  uint64_t target_segments = 0;
  uint64_t max_samples = 4'000'000'000;  ///< give up (Error) beyond this with a segment target
  uint64_t seed = 1;
  Box3 view_box;  ///< empty: the scene bounds
  /// Optional: the view space within the box (e.g. a game level's non-solid space). Sample
  /// origins outside it are rejected and drawn again, so origins are uniform in the view
  /// space; segments still run to their hits. Must be thread-safe and deterministic.
  std::function<bool(const Vec3&)> view_space;
  /// Empty view space detection (back-face hit: move the origin there and re-cast). kAuto
  /// enables it only when every object is a closed, consistently outward-oriented solid.
  /// A sample inside a solid re-casts from both exits and may give two segments.
  EmptySpaceMode empty_space = EmptySpaceMode::kAuto;
  int max_recasts = 8;        ///< re-casts per sample before it is dropped as stuck in solids
  uint32_t batch_size = 1024; ///< samples per random stream: fixes the output, not the threads
  /// The stream's first batch: batch k of this config is batch first_batch + k of the stream
  /// (each batch has its own random stream), so consecutive chunks of a stream, each sampled
  /// with its own first_batch, give the segments the whole stream gives (sample_in_chunks).
  uint64_t first_batch = 0;
  bool show_progress = true;  ///< progress bar on stderr (only when it is a terminal)
};

struct EmptySpaceDecision {
  bool enabled = false;
  std::string reason;
};
/// Whether empty space detection applies to this scene under `mode`, and why.
EmptySpaceDecision decide_empty_space(const Scene& scene, EmptySpaceMode mode);

struct SamplingStats {
  uint64_t samples = 0;       ///< samples whose segments the output holds
  uint64_t rays = 0;          ///< every ray cast, re-casts included
  uint64_t recast_rays = 0;   ///< rays re-cast by empty space detection
  uint64_t valid_segments = 0;
  uint64_t missed_both = 0;       ///< neither ray hit anything: not a visibility segment
  uint64_t stuck_in_solid = 0;    ///< still inside solids after max_recasts
  uint64_t outside_view_box = 0;  ///< no length inside the view box (re-cast past its boundary)
  /// Samples inside a solid re-cast from both exits: each has two outcomes, so
  /// valid - see_through_segments + missed_both + stuck + outside == samples + two_sided_samples.
  uint64_t two_sided_samples = 0;
  /// Origins drawn outside SamplerConfig::view_space and drawn again (not samples).
  uint64_t rejected_origins = 0;
  /// See-through objects (ObjectInfo::occluder false) of the scene; segments crossing them get
  /// a companion segment seeing each at both ends (counted in valid_segments too), found by
  /// see_through_rays rays against their triangles (not in `rays`).
  uint64_t see_through_objects = 0, see_through_segments = 0, see_through_rays = 0;
  EmptySpaceDecision empty_space;
  Box3 view_box;
  bool view_box_from_scene = true;
  double seconds = 0;
  std::vector<uint64_t> segments_per_object;  ///< segments seeing each object at either end
};

struct SamplingResult {
  SegmentSet segments;
  SamplingStats stats;
};

/// Draws config.samples samples (or until config.target_segments segments exist). Throws
/// Error for an empty scene, a view box of zero volume, or a segment target out of reach.
SamplingResult sample_segments(const Scene& scene, const RayCaster& caster, const SamplerConfig& config);

/// Adds the counts, times and segments per object of `more` (another part of the same stream)
/// to `total`; the rest of `total` (view box, empty space, see-through objects) stays.
void add_sampling_stats(SamplingStats& total, const SamplingStats& more);

/// Draws config.samples samples (no segment target) in consecutive chunks of about
/// `chunk_samples` (a multiple of the batch size), and hands each chunk's segments to `use`
/// before the next is drawn: the chunks together are the segments sample_segments(scene, caster,
/// config) gives, in order, but at most one chunk is held at a time; `use` also gets the samples
/// drawn so far, this chunk's included. Returns the statistics of the whole stream (times
/// summed; segments_per_object and the rest as sample_segments gives).
SamplingStats sample_in_chunks(const Scene& scene, const RayCaster& caster, const SamplerConfig& config,
                               uint64_t chunk_samples,
                               const std::function<void(const SegmentSet& chunk, uint64_t samples_so_far)>& use);

/// Casts samples whose origins and directions the caller chooses (AGVS's distributions) by the
/// sampler's rule: forward and backward rays, empty view space detection, see-through
/// objects, clipping to the view box. Thread-safe: each thread has its own scratch.
class SegmentCaster {
 public:
  SegmentCaster(const Scene& scene, const RayCaster& caster, const Box3& view_box,
                EmptySpaceMode mode = EmptySpaceMode::kAuto, int max_recasts = 8);
  ~SegmentCaster();
  /// The segments of the samples (points[i], dirs[i]) into `out` (replaced): those of the
  /// first rays in sample order, then those of re-casts; sample_of[k] is the sample of
  /// segment k. Returns the rays cast. The scene and caster must outlive this object.
  uint64_t cast(std::span<const Vec3> points, std::span<const Vec3> dirs, SegmentSet& out,
                std::vector<uint32_t>& sample_of) const;
  const EmptySpaceDecision& empty_space() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Every ray sample_segments(scene, caster, config) casts, re-casts included, in batch order
/// (the forward and backward ray of a sample first, then its batch's re-casts). Runs the
/// sampler again, untimed: for measuring bare Embree on exactly the sampler's rays.
std::vector<Ray> sampled_rays(const Scene& scene, const RayCaster& caster, const SamplerConfig& config);

}  // namespace viewcells
