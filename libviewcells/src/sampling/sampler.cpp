// Visibility segment sampling, view-cell-construction paper section 4.1, with empty view space
// detection (figure 5). Directions: phi = 2 pi u1, cos(theta) = 1 - 2 u2 (uniform on the sphere).
#include "viewcells/sampling/sampler.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>

#include <cmath>
#include <limits>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/ranks.h"
#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells {

namespace {

/// Uniform on the sphere: cos(theta) = 1 - 2 u, and (cos phi, sin phi) from a uniform point
/// of the unit disc (rejection, 21% rejected) rather than sincos(2 pi u): the same
/// distribution as the paper's phi = 2 pi u1, without trigonometry in the hot loop.
Vec3 sample_direction(Rng& rng) {
  double x, y, r2;
  do {
    x = 2.0 * rng.uniform() - 1.0;
    y = 2.0 * rng.uniform() - 1.0;
    r2 = x * x + y * y;
  } while (r2 > 1.0 || r2 < 1e-12);
  const double cos_theta = 1.0 - 2.0 * rng.uniform();
  const double scale = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta) / r2);
  return {x * scale, y * scale, cos_theta};
}

Vec3 clamp_to_box(const Vec3& p, const Box3& b) { return max(b.lo, min(b.hi, p)); }

/// Consecutive origins outside the view space after which it is taken to be empty.
constexpr uint64_t kMaxRejections = 1'000'000;

/// Draws the points and directions of the `count` samples of batch `batch`; origins outside
/// `view_space` (when given) are drawn again and counted in `rejected`.
void draw_batch(uint64_t seed, uint64_t batch, size_t count, const Box3& box,
                const std::function<bool(const Vec3&)>& view_space, std::vector<Vec3>& points,
                std::vector<Vec3>& dirs, uint64_t& rejected) {
  Rng rng(seed, batch);
  points.resize(count);
  dirs.resize(count);
  const Vec3 e = box.extent();
  for (size_t i = 0; i < count; ++i) {
    uint64_t misses = 0;
    do {
      points[i] = {box.lo.x + e.x * rng.uniform(), box.lo.y + e.y * rng.uniform(), box.lo.z + e.z * rng.uniform()};
      if (!view_space || view_space(points[i])) break;
      if (++misses == kMaxRejections)
        throw Error("no sample origin in the view space after " + std::to_string(kMaxRejections) +
                    " tries: is the view space empty within the view box?");
    } while (true);
    rejected += misses;
    dirs[i] = sample_direction(rng);
  }
}

/// What one batch produced: its segments are the first `valid` of its scratch set.
struct BatchOutput {
  size_t valid = 0;
  uint64_t rays = 0, recast_rays = 0, missed_both = 0, stuck = 0, outside = 0, two_sided = 0, rejected = 0;
  uint64_t see_through_rays = 0, see_through_segments = 0;
};

class BatchSampler {
 public:
  /// `beyond`: a distance from any point of the box past which no object lies (for lines of
  /// sight that see nothing at one end).
  BatchSampler(const RayCaster& caster, const RayCaster* see_through, const Box3& box,
               const std::function<bool(const Vec3&)>& view_space, bool esd, int max_recasts, double recast_eps,
               double beyond)
      : caster_(caster),
        see_through_(see_through),
        beyond_(beyond),
        box_(box),
        view_space_(view_space),
        esd_(esd),
        max_recasts_(max_recasts),
        eps_(recast_eps) {}

  /// At most one segment per sample, or two when a sample inside a solid re-casts both ways.
  static size_t segments_per_sample(bool esd) { return esd ? 2 : 1; }

  /// Samples batch `batch` and writes its valid segments to `segs` from index 0 on (scratch
  /// slots: at most segments_per_sample() * count of them); out.valid says how many.
  void run(uint64_t seed, uint64_t batch, size_t count, SegmentSet& segs, BatchOutput& out,
           std::vector<Ray>* log = nullptr) {
    draw_batch(seed, batch, count, box_, view_space_, points_, dirs_, out.rejected);
    sample_of_ = nullptr;
    cast_drawn(count, segs, out, log);
  }

  /// The same for samples given by the caller; sample_of[k] receives the sample of segment k.
  void run_given(std::span<const Vec3> points, std::span<const Vec3> dirs, SegmentSet& segs, BatchOutput& out,
                 std::vector<uint32_t>& sample_of) {
    points_.assign(points.begin(), points.end());
    dirs_.assign(dirs.begin(), dirs.end());
    sample_of.clear();
    sample_of_ = &sample_of;
    cast_drawn(points.size(), segs, out, nullptr);
    sample_of_ = nullptr;
  }

 private:
  /// Casts the samples in points_, dirs_.
  void cast_drawn(size_t count, SegmentSet& segs, BatchOutput& out, std::vector<Ray>* log) {
    segs_ = &segs;
    sights_.clear();
    hits_.resize(2 * count);
    caster_.intersect_pairs(points_, dirs_, hits_);
    if (log) {
      for (size_t i = 0; i < count; ++i) {
        log->push_back(Ray{points_[i], dirs_[i]});
        log->push_back(Ray{points_[i], -dirs_[i]});
      }
    }
    out.rays += 2 * count;
    pending_.clear();

    for (size_t i = 0; i < count; ++i) {
      current_ = static_cast<uint32_t>(i);
      const Hit& fwd = hits_[2 * i];
      const Hit& bwd = hits_[2 * i + 1];
      const bool fwd_inside = fwd.hit() && !fwd.front, bwd_inside = bwd.hit() && !bwd.front;
      if (esd_ && (fwd_inside || bwd_inside)) {
        // The origin lies inside a solid: continue from where the ray leaves it (figure 5).
        // Both rays leave the solid, so re-cast from both exits: two free segments for four
        // rays, where the paper's forward-only shift gives one for three. The PVS of a cell
        // is a union, so what matters is which segments are found, not how often.
        out.two_sided += fwd_inside && bwd_inside;
        if (fwd_inside) recast_from(points_[i] + dirs_[i] * fwd.t, dirs_[i], fwd.object, fwd.triangle, 1, out);
        if (bwd_inside) recast_from(points_[i] - dirs_[i] * bwd.t, -dirs_[i], bwd.object, bwd.triangle, 1, out);
        continue;
      }
      emit(points_[i], dirs_[i], bwd.hit() ? -bwd.t : -INFINITY, bwd.object, bwd.triangle,
           fwd.hit() ? fwd.t : INFINITY, fwd.object, fwd.triangle, out);
    }

    // Re-cast from the exit points, in batches, until every sample has left the solids.
    while (!pending_.empty()) {
      recast_rays_.resize(pending_.size());
      recast_hits_.resize(pending_.size());
      for (size_t k = 0; k < pending_.size(); ++k)
        recast_rays_[k] = Ray{pending_[k].origin, pending_[k].dir, eps_};
      caster_.intersect(recast_rays_, recast_hits_);
      if (log) log->insert(log->end(), recast_rays_.begin(), recast_rays_.end());
      out.rays += pending_.size();
      out.recast_rays += pending_.size();
      next_.clear();
      for (size_t k = 0; k < pending_.size(); ++k) {
        const Pending& p = pending_[k];
        const Hit& h = recast_hits_[k];
        current_ = p.sample;
        if (h.hit() && !h.front) {  // left one solid straight into another
          if (p.depth >= max_recasts_) {
            ++out.stuck;
          } else {
            recast_from(p.origin + p.dir * h.t, p.dir, h.object, h.triangle, p.depth + 1, out);
          }
          continue;
        }
        // The near end is the exit surface, seen (front side) from the segment.
        emit(p.origin, p.dir, 0.0, p.exit_object, p.exit_triangle, h.hit() ? h.t : INFINITY, h.object, h.triangle,
             out);
      }
      pending_.swap(next_);
    }
    if (see_through_) add_see_through(out);
  }

  /// Every see-through object a segment's line of sight crosses is seen from all of the
  /// segment: one more segment, the same line with that object at both ends. The line of sight
  /// runs between the objects its ends see (to infinity past an end that sees nothing), also
  /// where it lies outside the view box: a pane beyond the box is seen through from inside it.
  void add_see_through(BatchOutput& out) {
    const size_t primary = out.valid;
    for (size_t i = 0; i < primary; ++i) {
      const Sight& s = sights_[i];
      // Along the line from its near end: the object seen there, or, when that end sees
      // nothing, a point beyond every object; in world units along a unit direction (a caller's
      // directions need not be unit). One scan, as many rays as crossings plus one.
      const double len = length(s.dir);
      if (!(len > 0)) continue;
      const Vec3 u = s.dir / len;
      const Vec3 a = segs_->a(i);
      const bool near_hit = std::isfinite(s.t0);
      const Vec3 start = near_hit ? s.origin + s.dir * s.t0 : a - u * beyond_;
      const double t_start = near_hit ? s.t0 : dot(start - s.origin, u) / len;  // in units of dir
      // Past each crossing by 1e-7 of the segment's length in the box, as the samplers stepped.
      const double step = 1e-7 * length(segs_->b(i) - a);
      crossed_.clear();
      cross(start, u, 0.0, std::isfinite(s.t1) ? (s.t1 - t_start) * len : s.t1, step, out);
      for (uint32_t o : crossed_) {
        if (out.valid >= segs_->size()) segs_->resize(2 * segs_->size() + 16);
        segs_->set(out.valid++, a, segs_->b(i), o, o, kNoObject, kNoObject);
        if (sample_of_) sample_of_->push_back((*sample_of_)[i]);
        ++out.see_through_segments;
      }
    }
  }

  /// Adds to crossed_, once each and in order, the see-through objects that o + t d crosses for t
  /// in [from, to] (to may be infinite), each `step` past the last: at most 64 crossings.
  void cross(const Vec3& o, const Vec3& d, double from, double to, double step, BatchOutput& out) {
    for (int k = 0; k < 64 && from < to; ++k) {
      const Hit h = see_through_->intersect(Ray{o, d, from, to});
      ++out.see_through_rays;
      if (!h.hit()) return;
      if (std::find(crossed_.begin(), crossed_.end(), h.object) == crossed_.end()) crossed_.push_back(h.object);
      from = h.t + step;  // past this crossing
    }
  }

  /// Queues a re-cast from the exit point `origin` of a solid (into next_ while re-casting,
  /// else pending_). An exit point outside the (convex) view box means the ray has left the
  /// box for good, so the segment it would give has no length inside: not worth a ray.
  void recast_from(const Vec3& origin, const Vec3& dir, uint32_t object, uint32_t triangle, int depth,
                   BatchOutput& out) {
    if (!box_.contains(origin, eps_)) {
      ++out.outside;
      return;
    }
    (depth == 1 ? pending_ : next_).push_back({origin, dir, object, triangle, depth, current_});
  }

 private:
  struct Pending {
    Vec3 origin, dir;
    uint32_t exit_object, exit_triangle;
    int depth;
    uint32_t sample;  ///< index of the sample in its batch
  };
  /// A valid segment's whole line of sight, o + t d for t in [t0, t1] (infinite past an end
  /// that sees nothing), before clipping to the box: where see-through objects are looked for.
  struct Sight {
    Vec3 origin, dir;
    double t0, t1;
  };
  std::vector<Sight> sights_;  ///< per valid segment of the batch, when the scene sees through
  uint32_t current_ = 0;                        ///< the sample being emitted
  std::vector<uint32_t>* sample_of_ = nullptr;  ///< when set: the sample of each segment

  /// The segment o + t*d, t in [t0, t1], seeing object o0 at t0 and o1 at t1, clipped to the box.
  void emit(const Vec3& o, const Vec3& d, double t0, uint32_t o0, uint32_t tri0, double t1, uint32_t o1, uint32_t tri1,
            BatchOutput& out) {
    if (o0 == kNoObject && o1 == kNoObject) {
      ++out.missed_both;
      return;
    }
    // Fast path: both ends are hits inside the box (always so with the default box, the scene
    // bounds, up to rounding); no clipping needed.
    if (std::isfinite(t0) && std::isfinite(t1) && t1 - t0 > eps_) {
      const Vec3 a = o + d * t0, b = o + d * t1;
      if (box_.contains(a, eps_) && box_.contains(b, eps_)) {
        segs_->set(out.valid++, clamp_to_box(a, box_), clamp_to_box(b, box_), o0, o1, tri0, tri1);
        if (sample_of_) sample_of_->push_back(current_);
        if (see_through_) sights_.push_back({o, d, t0, t1});
        return;
      }
    }
    // A segment needs length inside the box. Re-cast segments can fail this: the exit surface
    // of a solid may lie on (or beyond) the box boundary, e.g. a facade on the scene bounds.
    double c0, c1;
    if (!clip_line_to_box(box_, o, d, c0, c1) || std::min(t1, c1) - std::max(t0, c0) <= eps_) {
      ++out.outside;
      return;
    }
    // Hits beyond the box keep their object: it is visible from the part inside the box.
    const Vec3 a = clamp_to_box(o + d * std::max(t0, c0), box_);
    const Vec3 b = clamp_to_box(o + d * std::min(t1, c1), box_);
    segs_->set(out.valid++, a, b, o0, o1, tri0, tri1);
    if (sample_of_) sample_of_->push_back(current_);
    if (see_through_) sights_.push_back({o, d, t0, t1});
  }

  const RayCaster& caster_;
  const RayCaster* see_through_;  ///< see-through triangles, or null when the scene has none
  double beyond_;
  std::vector<uint32_t> crossed_;
  Box3 box_;
  const std::function<bool(const Vec3&)>& view_space_;
  bool esd_;
  int max_recasts_;
  double eps_;
  SegmentSet* segs_ = nullptr;
  std::vector<Vec3> points_, dirs_;
  std::vector<Hit> hits_;
  std::vector<Ray> recast_rays_;
  std::vector<Hit> recast_hits_;
  std::vector<Pending> pending_, next_;
};

/// Re-cast rays start a little past the exit surface: 1e-6 of the scene diagonal is well above
/// Embree's float resolution in its local frame and well below the generators' 2 mm gaps.
double recast_epsilon(const Scene& scene, const Box3& view_box) {
  return 1e-6 * std::max(scene.bounds.diagonal(), view_box.diagonal());
}

/// A distance from any point of `box` past which no object of `scene` lies: the diagonal of
/// both together, and one more unit.
double beyond(const Scene& scene, const Box3& box) {
  Box3 all = box;
  all.extend(scene.bounds);
  return all.diagonal() + 1.0;
}

/// Objects one sees through (water, glass) do not stop rays: where segments cross them is found
/// against their own triangles. Null when the scene has none.
std::unique_ptr<RayCaster> make_see_through_caster(const Scene& scene, uint64_t* count) {
  const uint64_t n = static_cast<uint64_t>(
      std::count_if(scene.objects.begin(), scene.objects.end(), [](const ObjectInfo& o) { return !o.occluder; }));
  if (count) *count = n;
  if (n == 0) return nullptr;
  EmbreeConfig ec;
  ec.see_through = true;
  return make_embree_caster(scene, ec);
}

Box3 resolve_view_box(const Scene& scene, const SamplerConfig& config, bool& from_scene) {
  if (scene.triangles.empty()) throw Error("cannot sample an empty scene");
  from_scene = config.view_box.empty();
  const Box3 box = from_scene ? scene.bounds : config.view_box;
  if (!is_finite(box.lo) || !is_finite(box.hi)) throw Error("view space box has non-finite coordinates");
  if (!(box.volume() > 0))
    throw Error(std::string("the view space box has zero volume") +
                (from_scene ? " (the scene is flat: give a view box with --view-box)" : ""));
  return box;
}

}  // namespace

namespace {

/// A batch's counts added to the run's.
void add_batch_stats(SamplingStats& stats, const BatchOutput& out, uint64_t count) {
  stats.samples += count;
  stats.rays += out.rays;
  stats.recast_rays += out.recast_rays;
  stats.missed_both += out.missed_both;
  stats.stuck_in_solid += out.stuck;
  stats.outside_view_box += out.outside;
  stats.two_sided_samples += out.two_sided;
  stats.rejected_origins += out.rejected;
  stats.see_through_rays += out.see_through_rays;
  stats.see_through_segments += out.see_through_segments;
}

/// Sampling on several ranks: rounds of a fixed number of batches (not depending on the
/// ranks); each rank samples the batches it owns, every rank receives all of them and hands
/// them to `consume` in batch order (until `finished`), so every rank holds the same output,
/// the one a single process makes.
template <class Samplers, class Consume>
void sample_on_ranks(const SamplerConfig& config, Samplers& samplers, size_t slots, uint64_t limit,
                     const Box3& view_box, const bool& finished, Consume& consume) {
  uint64_t next_batch = 0;
  constexpr uint64_t kRoundBatches = 64;
  SegmentSet batch_segs;
  while (!finished) {
    throw_if_interrupted("sampling");
    const uint64_t first = next_batch;
    uint64_t n = 0;
    while (n < kRoundBatches && (first + n) * config.batch_size < limit) ++n;
    if (n == 0) break;
    std::vector<std::string> items(n);
    tbb::parallel_for(uint64_t{0}, n, [&](uint64_t i) {
      const uint64_t batch = first + i;
      if (!ranks::mine(batch)) return;
      SegmentSet scratch;
      scratch.resize(slots);
      BatchOutput out;
      samplers.local().run(config.seed, config.first_batch + batch,
                           std::min<uint64_t>(config.batch_size, limit - batch * config.batch_size), scratch, out, nullptr);
      ByteWriter w;
      w.put(out);
      scratch.resize(out.valid);
      put_segments(w, scratch);
      items[i] = w.take();
    });
    ranks::share(items, first);  // item i is batch first + i, owned by mine(first + i)
    for (uint64_t i = 0; i < n && !finished; ++i) {
      const uint64_t batch = first + i;
      ByteReader r(items[i], "a rank's sampling results");
      BatchOutput out = r.get<BatchOutput>();
      batch_segs.view_box = view_box;
      get_segments(r, batch_segs, items[i].size());
      consume(batch_segs, out, std::min<uint64_t>(config.batch_size, limit - batch * config.batch_size), nullptr);
    }
    next_batch = first + n;
  }
}

/// Each object's segments (an end on it) into stats.segments_per_object.
void count_segments_per_object(SamplingStats& stats, const SegmentSet& segs, size_t objects) {
  stats.segments_per_object.assign(objects, 0);
  for (size_t i = 0; i < segs.size(); ++i) {
    if (segs.object_a[i] != kNoObject) ++stats.segments_per_object[segs.object_a[i]];
    if (segs.object_b[i] != kNoObject && segs.object_b[i] != segs.object_a[i])
      ++stats.segments_per_object[segs.object_b[i]];
  }
}

/// The sampler; `logs`, when given, receives the rays of each batch in the output, in order.
constexpr uint64_t kGiveUpSamples = 1'000'000;

SamplingResult sample_impl(const Scene& scene, const RayCaster& caster, const SamplerConfig& config,
                           std::vector<std::vector<Ray>>* logs) {
  if (config.batch_size == 0) throw Error("batch size must be positive");
  if (config.samples == 0 && config.target_segments == 0) throw Error("nothing to sample: samples and segments are 0");
  SamplingResult result;
  SamplingStats& stats = result.stats;
  stats.view_box = resolve_view_box(scene, config, stats.view_box_from_scene);
  stats.empty_space = decide_empty_space(scene, config.empty_space);
  SegmentSet& segs = result.segments;
  segs.view_box = stats.view_box;

  const double eps = recast_epsilon(scene, stats.view_box);
  std::unique_ptr<RayCaster> see_through = make_see_through_caster(scene, &stats.see_through_objects);
  tbb::enumerable_thread_specific<BatchSampler> samplers(
      [&] { return BatchSampler(caster, see_through.get(), stats.view_box, config.view_space,
                                stats.empty_space.enabled, config.max_recasts, eps, beyond(scene, stats.view_box)); });
  const bool by_segments = config.target_segments > 0;
  Progress progress(by_segments ? "segments" : "sampling", by_segments ? config.target_segments : config.samples);
  const bool show = config.show_progress;
  const auto start = std::chrono::steady_clock::now();

  // A pipeline over the stream of batches: drawn in order, sampled in parallel, appended to
  // the output in batch order. The output is therefore a prefix of the same stream for any
  // thread count; with a segment target it is cut at the target-th segment and the stream
  // stops there, so no more than the batches in flight are cast past the target. Each batch
  // writes into scratch slots of its token, reused: the output is written once, densely.
  const uint64_t limit = by_segments ? config.max_samples : config.samples;
  const size_t slots = BatchSampler::segments_per_sample(stats.empty_space.enabled) * config.batch_size;
  struct Token {
    SegmentSet segments;
    BatchOutput out;
    uint64_t batch = 0;
    size_t count = 0;
    std::vector<Ray> log;
  };
  const size_t token_count = 4 * static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  std::vector<Token> tokens(token_count);
  for (Token& t : tokens) t.segments.resize(slots);
  // Room for the expected output (virtual until touched), capped: beyond it the arrays grow.
  segs.reserve_for_output(std::min<uint64_t>(by_segments ? config.target_segments : config.samples, 1ull << 25));
  uint64_t next_batch = 0;
  bool done = false;      // the target is reached (output stage only)
  bool finished = false;  // nothing more goes into the output (output stage only)
  std::atomic<bool> stop{false};
  // The output stage: batches arrive here in batch order.
  auto consume = [&](const SegmentSet& batch_segs, BatchOutput& out, uint64_t count, std::vector<Ray>* log) {
    if (finished) return;  // in flight when the stream stopped: not part of the output
    if (by_segments && segs.size() + out.valid >= config.target_segments) {
      out.valid = config.target_segments - segs.size();  // the rest of this batch is dropped
      done = finished = true;
    }
    segs.append(batch_segs, 0, out.valid);
    if (logs) logs->push_back(std::move(*log));
    add_batch_stats(stats, out, count);
    if (show) progress.advance(by_segments ? out.valid : count);
    // Nothing seen after a million samples: the target is out of reach, say so now.
    if (by_segments && segs.size() == 0 && stats.samples >= kGiveUpSamples) finished = true;
    if (finished) stop.store(true, std::memory_order_relaxed);
  };
  if (ranks::size() > 1 && !logs) {
    sample_on_ranks(config, samplers, slots, limit, segs.view_box, finished, consume);
  } else {
    tbb::parallel_pipeline(
        token_count,
        tbb::make_filter<void, Token*>(tbb::filter_mode::serial_in_order,
                                       [&](tbb::flow_control& fc) -> Token* {
                                         const uint64_t first = next_batch * config.batch_size;
                                         if (stop.load(std::memory_order_relaxed) || first >= limit) {
                                           fc.stop();
                                           return nullptr;
                                         }
                                         // In-flight batches are consecutive and at most token_count.
                                         Token* t = &tokens[next_batch % token_count];
                                         t->batch = next_batch++;
                                         t->count = std::min<uint64_t>(config.batch_size, limit - first);
                                         return t;
                                       }) &
            tbb::make_filter<Token*, Token*>(tbb::filter_mode::parallel,
                                             [&](Token* t) {
                                               t->out = BatchOutput{};
                                               t->log.clear();
                                               if (stop.load(std::memory_order_relaxed)) return t;
                                               samplers.local().run(config.seed, config.first_batch + t->batch,
                                                                    t->count, t->segments,
                                                                    t->out, logs ? &t->log : nullptr);
                                               return t;
                                             }) &
            tbb::make_filter<Token*, void>(tbb::filter_mode::serial_in_order,
                                           [&](Token* t) { consume(t->segments, t->out, t->count, &t->log); }));
  }
  stats.valid_segments = segs.size();
  if (by_segments && !done)
    throw Error("gave up after " + std::to_string(stats.samples) + " samples with only " +
                std::to_string(segs.size()) + " segments: do rays hit anything in this view box?");
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (show) progress.finish();

  count_segments_per_object(stats, segs, scene.objects.size());
  return result;
}

}  // namespace

SamplingResult sample_segments(const Scene& scene, const RayCaster& caster, const SamplerConfig& config) {
  return sample_impl(scene, caster, config, nullptr);
}

void add_sampling_stats(SamplingStats& total, const SamplingStats& s) {
  total.samples += s.samples;
  total.rays += s.rays;
  total.recast_rays += s.recast_rays;
  total.valid_segments += s.valid_segments;
  total.missed_both += s.missed_both;
  total.stuck_in_solid += s.stuck_in_solid;
  total.outside_view_box += s.outside_view_box;
  total.two_sided_samples += s.two_sided_samples;
  total.rejected_origins += s.rejected_origins;
  total.see_through_segments += s.see_through_segments;
  total.see_through_rays += s.see_through_rays;
  total.seconds += s.seconds;
  if (total.segments_per_object.size() < s.segments_per_object.size())
    total.segments_per_object.resize(s.segments_per_object.size(), 0);
  for (size_t o = 0; o < s.segments_per_object.size(); ++o) total.segments_per_object[o] += s.segments_per_object[o];
}

SamplingStats sample_in_chunks(const Scene& scene, const RayCaster& caster, const SamplerConfig& config,
                               uint64_t chunk_samples,
                               const std::function<void(const SegmentSet&, uint64_t)>& use) {
  if (config.target_segments > 0) throw Error("sampling in chunks needs a sample count, not a segment target");
  if (config.batch_size == 0) throw Error("batch size must be positive");
  if (config.samples == 0) throw Error("nothing to sample: samples and segments are 0");
  const uint64_t per_chunk = std::max<uint64_t>(1, chunk_samples / config.batch_size) * config.batch_size;
  SamplingStats total;
  Progress progress("sampling", config.samples);
  for (uint64_t first = 0; first < config.samples; first += per_chunk) {
    SamplerConfig c = config;
    c.samples = std::min(per_chunk, config.samples - first);
    c.first_batch = config.first_batch + first / config.batch_size;
    c.show_progress = false;
    SamplingResult r = sample_segments(scene, caster, c);
    if (first == 0) total = r.stats;
    else add_sampling_stats(total, r.stats);
    use(r.segments, first + c.samples);
    if (config.show_progress) progress.advance(c.samples);
  }
  if (config.show_progress) progress.finish();
  return total;
}

struct SegmentCaster::Impl {
  std::unique_ptr<RayCaster> see_through;
  std::function<bool(const Vec3&)> no_view_space;
  EmptySpaceDecision esd;
  tbb::enumerable_thread_specific<BatchSampler> samplers;
  Impl(const Scene& scene, const RayCaster& caster, const Box3& box, EmptySpaceMode mode, int max_recasts)
      : see_through(make_see_through_caster(scene, nullptr)),
        esd(decide_empty_space(scene, mode)),
        samplers([this, &caster, box, max_recasts, eps = recast_epsilon(scene, box), far = beyond(scene, box)] {
          return BatchSampler(caster, see_through.get(), box, no_view_space, esd.enabled, max_recasts, eps, far);
        }) {}
};

SegmentCaster::SegmentCaster(const Scene& scene, const RayCaster& caster, const Box3& view_box, EmptySpaceMode mode,
                             int max_recasts) {
  if (view_box.empty() || !(view_box.volume() > 0)) throw Error("the view space box has zero volume");
  impl_ = std::make_unique<Impl>(scene, caster, view_box, mode, max_recasts);
}

SegmentCaster::~SegmentCaster() = default;

const EmptySpaceDecision& SegmentCaster::empty_space() const { return impl_->esd; }

uint64_t SegmentCaster::cast(std::span<const Vec3> points, std::span<const Vec3> dirs, SegmentSet& out,
                             std::vector<uint32_t>& sample_of) const {
  if (points.size() != dirs.size()) throw Error("SegmentCaster: as many directions as points are needed");
  out.resize(BatchSampler::segments_per_sample(impl_->esd.enabled) * points.size());
  BatchOutput o;
  impl_->samplers.local().run_given(points, dirs, out, o, sample_of);
  out.resize(o.valid);
  return o.rays + o.see_through_rays;
}

std::vector<Ray> sampled_rays(const Scene& scene, const RayCaster& caster, const SamplerConfig& config) {
  std::vector<std::vector<Ray>> logs;
  SamplerConfig quiet = config;
  quiet.show_progress = false;
  sample_impl(scene, caster, quiet, &logs);
  size_t total = 0;
  for (const auto& l : logs) total += l.size();
  std::vector<Ray> rays;
  rays.reserve(total);
  for (const auto& l : logs) rays.insert(rays.end(), l.begin(), l.end());
  return rays;
}

}  // namespace viewcells
