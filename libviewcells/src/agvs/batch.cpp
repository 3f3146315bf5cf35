// AGVS paper 4.1: one batch of global visibility sampling: draw the samples, cast them, and
// apply their segments to the PVSs of every cell they pierce, in sample order. The batch is
// the unit of determinism: its samples come from its own random stream, parallel work is cut
// into fixed chunks, and everything that depends on order is applied serially.
#include "solver_impl.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <chrono>
#include <span>
#include <tuple>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/cluster.h"

namespace viewcells {

namespace {

/// The view space-direction samples last: they also replace the draws that failed (no
/// mutation candidate left, a degenerate two-point pair), so every batch has n samples.
constexpr int kOrder[kDists] = {kSil, kTpm, kOd, kTp, kVsd};

struct SilhouetteJob {
  Candidate candidate;
  double u[2] = {0, 0};
  int n = 0;
  Vec3 points[2], dirs[2];
  uint64_t rays = 0;
};

}  // namespace

/// A batch's samples, grouped by distribution so that each distribution's rays are counted
/// exactly: samples first_of[d] .. end_of[d] - 1 are distribution d's.
struct AgvsSolver::Impl::BatchSamples {
  std::vector<Vec3> points, dirs;
  std::vector<int32_t> ref_cell;  ///< REF: the cell each sample belongs to
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
  SegmentSet segs;
  std::vector<uint32_t> sample_of;
  /// Every (segment, cell) with the segment having length in the cell, in segment order (not for
  /// REF); on several ranks only those of this rank's cells (cell mod ranks == rank).
  struct CellPair {
    uint32_t segment;  ///< index in the chunk
    int32_t cell;
  };
  std::vector<CellPair> pairs;
  uint64_t pierced = 0;  ///< all ranks' pairs
  uint64_t rays = 0;
  size_t seg_start = 0;  ///< index of its first segment among the batch's
};

namespace {
/// Lane l's share of n draws.
uint32_t lane_share(uint32_t n, size_t lanes, size_t l) {
  return static_cast<uint32_t>(n / lanes + (l < n % lanes ? 1 : 0));
}
/// Lane l's random stream in batch `index`: lane 0's is the batch's own (one lane draws as the
/// single buffer did).
uint64_t lane_stream(uint64_t index, size_t l) { return 1000 + index + (static_cast<uint64_t>(l) << 40); }
}  // namespace

uint32_t AgvsSolver::Impl::draw_mutations(uint64_t index, const uint32_t want[kDists], BatchSamples& s) {
  const auto start = std::chrono::steady_clock::now();
  // Each of this rank's lanes takes its candidates and random numbers in order; the silhouette
  // searches then run in parallel over all of them.
  // Per lane: its samples of the two mutations (0: silhouette, 1: two-point), in order.
  constexpr int kMutations[2] = {kSil, kTpm};
  struct LaneCounts {  // what every rank learns of a lane (the points are only its owner's)
    uint64_t samples[2] = {0, 0}, failed = 0, discovery_rays = 0;
  };
  struct LaneDraw {
    std::vector<SilhouetteJob> sil;
    std::vector<Vec3> points[2], dirs[2];
    LaneCounts counts;
  };
  const size_t n_lanes = lanes.size();
  std::vector<LaneDraw> draws(n_lanes);
  tbb::parallel_for(size_t{0}, n_lanes, [&](size_t l) {
    if (!my_lane(l)) return;
    LaneDraw& ld = draws[l];
    MutationLane& lane = lanes[l];
    Rng rng(config.seed, lane_stream(index, l));
    for (uint32_t k = lane_share(want[kSil], n_lanes, l); k > 0; --k) {
      if (lane.silhouette.empty()) {
        ++ld.counts.failed;
        continue;
      }
      SilhouetteJob job;
      job.candidate = lane.silhouette.take();
      job.u[0] = rng.uniform(), job.u[1] = rng.uniform();
      ld.sil.push_back(job);
    }
    for (uint32_t k = lane_share(want[kTpm], n_lanes, l); k > 0; --k) {
      Vec3 p, dir;
      if (!draw_two_point_mutation(rng, lane, p, dir)) {
        ++ld.counts.failed;
        continue;
      }
      ld.points[1].push_back(p);
      ld.dirs[1].push_back(dir);
    }
  });
  std::vector<std::pair<uint32_t, uint32_t>> jobs;  // (lane, job)
  for (size_t l = 0; l < n_lanes; ++l)
    for (size_t j = 0; j < draws[l].sil.size(); ++j) jobs.push_back({static_cast<uint32_t>(l), static_cast<uint32_t>(j)});
  tbb::parallel_for(tbb::blocked_range<size_t>(0, jobs.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t j = r.begin(); j < r.end(); ++j) {
      SilhouetteJob& job = draws[jobs[j].first].sil[jobs[j].second];
      job.n = silhouette_samples(job.candidate, job.u, job.points, job.dirs, job.rays);
    }
  });
  std::vector<LaneCounts> counts(n_lanes);
  for (size_t l = 0; l < n_lanes; ++l) {
    LaneDraw& ld = draws[l];
    for (const SilhouetteJob& job : ld.sil) {
      ld.counts.discovery_rays += job.rays;
      if (job.n == 0) ++ld.counts.failed;
      for (int j = 0; j < job.n; ++j) {
        ld.points[0].push_back(job.points[j]);
        ld.dirs[0].push_back(job.dirs[j]);
      }
    }
    for (int m = 0; m < 2; ++m) ld.counts.samples[m] = ld.points[m].size();
    counts[l] = ld.counts;
  }
  if (cluster::size() > 1) {
    std::vector<std::string> items(n_lanes);
    for (size_t l = 0; l < n_lanes; ++l)
      if (my_lane(l)) {
        ByteWriter w;
        w.put(counts[l]);
        items[l] = w.take();
      }
    cluster::share(items, [&](size_t l) { return lane_owner(l); });
    for (size_t l = 0; l < n_lanes; ++l) {
      ByteReader r(items[l], "a rank's mutation draws");
      counts[l] = r.get<LaneCounts>();
      if (counts[l].samples[0] > 2 * want[kSil] || counts[l].samples[1] > want[kTpm])
        r.fail("more mutation samples than wanted");
    }
  }
  for (int m = 0; m < 2; ++m) {
    const int d = kMutations[m];
    s.first_of[d] = static_cast<uint32_t>(s.points.size());
    for (size_t l = 0; l < n_lanes; ++l) {
      const uint32_t first = static_cast<uint32_t>(s.points.size()), n = static_cast<uint32_t>(counts[l].samples[m]);
      if (n == 0) continue;
      s.lane_ranges.push_back({d, static_cast<uint32_t>(l), first, n});
      if (my_lane(l)) {
        s.points.insert(s.points.end(), draws[l].points[m].begin(), draws[l].points[m].end());
        s.dirs.insert(s.dirs.end(), draws[l].dirs[m].begin(), draws[l].dirs[m].end());
      } else {
        s.points.resize(first + n);
        s.dirs.resize(first + n);
      }
    }
    s.end_of[d] = static_cast<uint32_t>(s.points.size());
  }
  uint32_t failed = 0;
  for (const LaneCounts& c : counts) {
    failed += static_cast<uint32_t>(c.failed);
    s.discovery_rays += c.discovery_rays;
  }
  stats.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return failed;
}

void AgvsSolver::Impl::draw_samples(uint64_t index, uint32_t n, const double share[kDists], BatchSamples& s) {
  uint32_t want[kDists];
  uint32_t assigned = 0;
  for (int d = 0; d < kDists; ++d) assigned += want[d] = static_cast<uint32_t>(std::floor(share[d] * n));
  want[kVsd] += n - assigned;  // what rounding left over
  if (config.method == AgvsMethod::kRef) {
    // All view space-direction (shares()): a random cell, a uniform point in it (rejection in
    // its bounds), a random direction.
    Rng rng(config.seed, 1000 + index);
    for (uint32_t k = 0; k < n; ++k) {
      Vec3 p;
      const uint32_t c = static_cast<uint32_t>(rng.below(cells.cell_count()));
      const Box3& b = cells.cell_bounds(c);
      for (int tries = 0; tries < 1000; ++tries) {
        p = {rng.uniform(b.lo.x, b.hi.x), rng.uniform(b.lo.y, b.hi.y), rng.uniform(b.lo.z, b.hi.z)};
        if (cells.cell_at(p) == static_cast<int32_t>(c) && (!config.view_space || config.view_space(p))) break;
      }
      s.points.push_back(p);
      s.dirs.push_back(sphere_direction(rng.uniform(), rng.uniform()));
      s.ref_cell.push_back(static_cast<int32_t>(c));
    }
    s.end_of[kVsd] = n;
    return;
  }
  uint32_t failed = draw_mutations(index, want, s);
  // Quasi-random, from Halton indices alone: computed in parallel, taken in order.
  for (int d : kOrder) {
    if (d == kSil || d == kTpm) continue;
    s.first_of[d] = static_cast<uint32_t>(s.points.size());
    failed += stationary_samples(d, want[d] + (d == kVsd ? failed : 0), s.points, s.dirs);
    s.end_of[d] = static_cast<uint32_t>(s.points.size());
  }
}

void AgvsSolver::Impl::cast_ref_chunk(const BatchSamples& s, BatchChunk& c) const {
  // The paper's REF: one ray per sample, forward from the point; what it hits first goes into
  // the point's cell. Where closed solids make inside and outside (empty space detection), a
  // back face first means the point is inside a solid: no camera stands there, nothing is seen.
  // See-through surfaces the ray crosses are not followed.
  std::vector<Ray> rays(c.size);
  std::vector<Hit> hits(c.size);
  for (uint32_t k = 0; k < c.size; ++k) rays[k] = Ray{s.points[c.first + k], s.dirs[c.first + k]};
  caster_ref().intersect(rays, hits);
  c.rays = c.size;
  c.segs = SegmentSet{};
  c.segs.reserve(c.size);
  c.sample_of.clear();
  const double far = 2 * cells.view_box().diagonal();
  for (uint32_t k = 0; k < c.size; ++k) {
    const Hit& h = hits[k];
    const bool seen = h.hit() && (h.front || !stats.empty_space.enabled);
    const Vec3 end = rays[k].origin + rays[k].dir * (h.hit() ? h.t : far);
    c.segs.push_back(rays[k].origin, end, kNoObject, seen ? h.object : kNoObject);
    c.sample_of.push_back(k);
  }
}

std::vector<AgvsSolver::Impl::BatchChunk> AgvsSolver::Impl::cast_samples(const BatchSamples& s) {
  // Cast in fixed chunks within each distribution, in parallel; outputs in sample order.
  constexpr uint32_t kChunk = 1024;
  std::vector<BatchChunk> chunks;
  auto add_chunks = [&](int d, uint32_t first, uint32_t end, int32_t lane) {
    for (uint32_t f = first; f < end; f += kChunk) {
      BatchChunk c;
      c.first = f;
      c.size = std::min(kChunk, end - f);
      c.dist = d;
      c.lane = lane;
      chunks.push_back(std::move(c));
    }
  };
  for (int d : kOrder) {
    if (d != kSil && d != kTpm) {
      add_chunks(d, s.first_of[d], s.end_of[d], -1);
      continue;
    }
    // A mutation's samples in runs of one lane group each.
    const BatchSamples::LaneRange* run = nullptr;
    uint32_t end = 0;
    for (const BatchSamples::LaneRange& r : s.lane_ranges) {
      if (r.dist != d) continue;
      if (run && lane_group(r.lane) == lane_group(run->lane)) {
        end = r.first + r.size;
        continue;
      }
      if (run) add_chunks(d, run->first, end, static_cast<int32_t>(run->lane));
      run = &r, end = r.first + r.size;
    }
    if (run) add_chunks(d, run->first, end, static_cast<int32_t>(run->lane));
  }
  // A chunk: its samples cast, and the cells of each segment.
  auto cast_chunk = [&](BatchChunk& c) {
    if (config.method == AgvsMethod::kRef) {
      cast_ref_chunk(s, c);
      return;
    }
    c.rays = caster().cast(std::span<const Vec3>(s.points.data() + c.first, c.size),
                           std::span<const Vec3>(s.dirs.data() + c.first, c.size), c.segs, c.sample_of);
    std::vector<std::tuple<int32_t, double, double>> stack;
    std::vector<int32_t> pierced;
    for (size_t i = 0; i < c.segs.size(); ++i) {
      cells.cells_of_segment(c.segs.a(i), c.segs.b(i), pierced, stack);
      for (int32_t cell : pierced) c.pairs.push_back({static_cast<uint32_t>(i), cell});
    }
    c.pierced = c.pairs.size();
  };
  if (cluster::size() > 1) {
    // Several ranks: each casts the chunks it owns (numbered across batches, so that the work
    // turns round the ranks; a chunk's owner may differ between rank counts, its content does
    // not), and every rank receives all chunks. A mutation lane's chunks are its owner's, the
    // only rank that drew their points. A chunk's pairs travel sorted by the rank of their cell:
    // each rank keeps its own.
    std::vector<std::string> items(chunks.size());
    const uint64_t base = stats.batches * 4096;
    const uint64_t ranks = static_cast<uint64_t>(cluster::size());
    auto owner = [&](size_t k) {
      return chunks[k].lane >= 0 ? lane_owner(static_cast<size_t>(chunks[k].lane)) : static_cast<int>((base + k) % ranks);
    };
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) {
      if (owner(k) != cluster::rank()) return;
      BatchChunk& c = chunks[k];
      cast_chunk(c);
      ByteWriter w;
      w.put(c.rays);
      w.put_array(c.sample_of);
      put_segments(w, c.segs);
      w.put(c.pierced);
      std::vector<std::vector<BatchChunk::CellPair>> of_rank(ranks);
      for (const BatchChunk::CellPair& p : c.pairs) of_rank[static_cast<uint64_t>(p.cell) % ranks].push_back(p);
      for (const auto& pairs : of_rank) w.put_array(pairs);
      items[k] = w.take();
    });
    cluster::share(items, owner);
    for (size_t k = 0; k < chunks.size(); ++k) {
      BatchChunk& c = chunks[k];
      ByteReader r(items[k], "a rank's casting results");
      c.rays = r.get<uint64_t>();
      r.get_array(c.sample_of, items[k].size());
      get_segments(r, c.segs, items[k].size());
      c.pierced = r.get<uint64_t>();
      std::vector<BatchChunk::CellPair> pairs;
      for (uint64_t rank = 0; rank < ranks; ++rank) {
        r.get_array(pairs, items[k].size());
        if (rank != static_cast<uint64_t>(cluster::rank())) continue;
        for (const BatchChunk::CellPair& p : pairs)
          if (p.segment >= c.segs.size() || p.cell < 0 || static_cast<uint32_t>(p.cell) >= cells.cell_count() ||
              !cluster::mine(static_cast<uint64_t>(p.cell)))
            r.fail("a segment's cell is out of range");
        c.pairs = std::move(pairs);
      }
    }
  } else {
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) { cast_chunk(chunks[k]); });
  }
  size_t total = 0;
  for (BatchChunk& c : chunks) {
    c.seg_start = total;
    total += c.segs.size();
  }
  return chunks;
}

/// What applying a batch counted: per distribution, and the estimator's camera rays per sample
/// (0 when the sample's point is inside a solid: no camera stands there) and those that were
/// wrong pixels (an entry new to the point's cell).
struct AgvsSolver::Impl::BatchCounts {
  uint64_t contribution[kDists] = {}, rays[kDists] = {};
  std::vector<uint8_t> camera_rays, wrong_rays, has_segment;
};

template <class OnSegment>
void AgvsSolver::Impl::insert_segments(const BatchSamples& s, const std::vector<BatchChunk>& chunks,
                                       OnSegment&& on_segment, std::vector<uint32_t>& gains,
                                       std::vector<uint8_t>& flags, std::vector<uint8_t>& own) {
  const size_t total = gains.size();
  // Per segment: its chunk and index there, and whether it is its sample's camera segment (the
  // first of a view space-direction sample through the sample's point; a chunk holds its
  // samples' every segment), with the cell of that point.
  std::vector<std::pair<const BatchChunk*, uint32_t>> at(total);
  own.assign(total, 0);
  std::vector<int32_t> origin_cell(s.points.size(), -1);
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    std::vector<uint8_t> seen(c.size, 0);
    for (size_t i = 0; i < c.segs.size(); ++i) {
      const size_t k = c.seg_start + i;
      at[k] = {&c, static_cast<uint32_t>(i)};
      const uint32_t sample = c.first + c.sample_of[i];
      if (c.dist != kVsd || seen[c.sample_of[i]] || !on_segment(c, i, sample)) continue;
      seen[c.sample_of[i]] = 1;
      own[k] = 1;
      origin_cell[sample] = cells.cell_at(s.points[sample]);
    }
  });
  // This rank's cells divided among parts, each inserting into its own cells in sample order
  // (so the table, the gains and the flags do not depend on the number of parts): first the
  // (segment, cell) pairs of each part, per chunk, then each part's in order, the outcome kept
  // with each pair; then, per chunk, every pair's outcome added to its segment's. A rank walks
  // only the pairs of its own cells (the casting rank sorted them by rank).
  struct Pair {
    uint32_t segment;
    int32_t cell;
    uint32_t gain = 0;
    uint8_t flags = 0;
  };
  const uint64_t ranks = static_cast<uint64_t>(cluster::size());
  const size_t parts = static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  const size_t n_chunks = chunks.size();
  std::vector<std::vector<std::vector<Pair>>> pairs(n_chunks, std::vector<std::vector<Pair>>(parts));
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    for (const BatchChunk::CellPair& p : c.pairs)  // this rank's cells only
      pairs[ci][(static_cast<uint64_t>(p.cell) / ranks) % parts].push_back(
          {static_cast<uint32_t>(c.seg_start + p.segment), p.cell});
  });
  std::vector<uint64_t> part_entries(parts, 0);
  tbb::parallel_for(size_t{0}, parts, [&](size_t p) {
    for (size_t ci = 0; ci < n_chunks; ++ci)
      for (Pair& pair : pairs[ci][p]) {
        const BatchChunk& c = *at[pair.segment].first;
        const uint32_t i = at[pair.segment].second;
        const uint32_t objs[2] = {c.segs.object_a[i], c.segs.object_b[i]};
        const uint32_t cell = static_cast<uint32_t>(pair.cell);
        const bool origin = own[pair.segment] && pair.cell == origin_cell[c.first + c.sample_of[i]];
        bool contributed[2] = {false, false}, at_origin[2] = {false, false};
        pair.gain = contribute_in_cell([&](uint32_t o) { return pvs.insert_in_row(cell, o); }, objs, origin,
                                       contributed, at_origin);
        pair.flags = static_cast<uint8_t>(contributed[0] | contributed[1] << 1 | at_origin[0] << 2 | at_origin[1] << 3);
        part_entries[p] += pair.gain;
        if (config.filter_statistics) count_hits(pair.cell, objs[0], objs[1]);
      }
  });
  for (uint64_t n : part_entries) pvs.add_entries(n);
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    for (const std::vector<Pair>& of_part : pairs[ci])
      for (const Pair& pair : of_part) {
        gains[pair.segment] += pair.gain;
        flags[pair.segment] |= pair.flags;
      }
    const BatchChunk& c = chunks[ci];
    for (size_t i = 0; i < c.segs.size(); ++i) {
      // Both ends see the same object: both rays were wrong pixels before (as contribute()).
      const size_t k = c.seg_start + i;
      if (c.segs.object_a[i] == c.segs.object_b[i] && c.segs.object_a[i] != kNoObject)
        flags[k] = static_cast<uint8_t>((flags[k] & ~8u) | ((flags[k] & 4u) << 1));
    }
  });
}

void AgvsSolver::Impl::apply_segments(const BatchSamples& s, const std::vector<BatchChunk>& chunks,
                                      BatchCounts& counts) {
  // Pass 1, in sample order: the table. On several ranks each inserts into its own cells (c
  // mod ranks == rank); then each segment's gains are summed and its flags or-ed over the
  // ranks (in one process, every cell is its own and the reductions do nothing). Which
  // samples are the estimator's cameras (the first own segment of a view space-direction
  // sample) does not depend on the table, so every rank finds the same ones.
  size_t total = 0;
  for (const BatchChunk& c : chunks) total += c.segs.size();
  std::vector<uint32_t> gains(total, 0);
  std::vector<uint8_t> flags(total, 0);  // contributed a, b; at origin a, b (REF: wrong ray)
  std::vector<uint8_t> own;              // not REF: the segment is its sample's camera segment
  // Whether the sample's point lies on this segment: its own segment (re-casts of points
  // inside solids start elsewhere; see-through companions are the first one's).
  auto on_segment = [&](const BatchChunk& c, size_t i, uint32_t sample) {
    const Vec3 a = c.segs.a(i), ab = c.segs.b(i) - a;
    const double t = dot(s.points[sample] - a, ab);
    return t >= 0 && t <= dot(ab, ab);
  };
  if (config.method == AgvsMethod::kRef) {
    std::vector<uint8_t> camera(s.points.size(), 0);
    for (const BatchChunk& c : chunks) {
      for (size_t i = 0; i < c.segs.size(); ++i) {
        // Per cell: the object hit forward from the sample's point, for its cell only; one
        // camera ray, counted once per sample.
        const size_t k = c.seg_start + i;
        const uint32_t sample = c.first + c.sample_of[i];
        if (camera[sample] != 0 || !on_segment(c, i, sample)) continue;
        camera[sample] = 1;
        const int32_t cell = s.ref_cell[sample];
        if (!cluster::mine(static_cast<uint64_t>(cell))) continue;
        const uint32_t object = c.segs.object_b[i];
        if (config.filter_statistics) count_hits(cell, object, kNoObject);
        if (object != kNoObject && pvs.insert(static_cast<uint32_t>(cell), object)) gains[k] = 1, flags[k] = 4;
      }
    }
  } else {
    insert_segments(s, chunks, on_segment, gains, flags, own);
  }
  cluster::sum(gains);
  cluster::bit_or(flags);
  // Pass 2: what follows from the segments besides the table. Per chunk in parallel (a chunk
  // holds its samples' every segment): the counts, the estimator's camera rays, and the radii
  // at the ends of contributing segments (point location where an end has no object); then,
  // in sample order, the mutation candidates.
  const bool mutations = config.method == AgvsMethod::kAgvs;
  std::vector<uint64_t> chunk_contribution(chunks.size(), 0);
  std::vector<std::array<double, 2>> radius(mutations ? total : 0);
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    for (size_t i = 0; i < c.segs.size(); ++i) {
      const size_t k = c.seg_start + i;
      const uint32_t sample = c.first + c.sample_of[i];
      counts.has_segment[sample] = 1;
      chunk_contribution[ci] += gains[k];
      if (config.method == AgvsMethod::kRef) {
        if (counts.camera_rays[sample] == 0 && on_segment(c, i, sample)) {
          counts.camera_rays[sample] = 1;
          if (flags[k] & 4) counts.wrong_rays[sample] = 1;
        }
        continue;
      }
      // The estimator's rays: a camera at the point sees along both rays of its segment.
      if (own[k]) {
        counts.camera_rays[sample] = 2;
        counts.wrong_rays[sample] = static_cast<uint8_t>(((flags[k] >> 2) & 1) + ((flags[k] >> 3) & 1));
      }
      if (mutations && gains[k] > 0 && my_lane(sample % lanes.size()))  // its lane's owner feeds it
        radius[k] = {end_radius(c.segs.object_a[i], c.segs.a(i)), end_radius(c.segs.object_b[i], c.segs.b(i))};
    }
  });
  for (size_t ci = 0; ci < chunks.size(); ++ci) {
    counts.rays[chunks[ci].dist] += chunks[ci].rays;
    counts.contribution[chunks[ci].dist] += chunk_contribution[ci];
  }
  if (mutations) add_candidates(chunks, gains, flags, radius);
  if (cluster::size() == 1) return;
  // The table's size over all ranks' rows (for the mean PVS of the curve and the status).
  partitioned = true;
  std::vector<uint64_t> grown{pvs.entries() - synced_entries};
  cluster::sum(grown);
  global_entries = synced_entries + grown[0];
}

void AgvsSolver::Impl::add_candidates(const std::vector<BatchChunk>& chunks, const std::vector<uint32_t>& gains,
                                      const std::vector<uint8_t>& flags,
                                      const std::vector<std::array<double, 2>>& radius) {
  // A mutation candidate per end whose object contributed, into the lane of its sample (index
  // in the batch modulo the lanes). The contributing segments are sorted by lane (a counting
  // sort: per chunk and lane, then by offsets), keeping sample order within each lane; then
  // each lane takes its own in parallel. Every rank counts every lane's candidates.
  const auto clock_start = std::chrono::steady_clock::now();
  const size_t n_lanes = lanes.size(), n_chunks = chunks.size();
  auto lane_of = [&](const BatchChunk& c, size_t i) { return (c.first + c.sample_of[i]) % n_lanes; };
  std::vector<uint32_t> per(n_lanes * n_chunks, 0);  // [lane][chunk]: contributing segments
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    for (size_t i = 0; i < c.segs.size(); ++i)
      if (flags[c.seg_start + i] & 3) ++per[lane_of(c, i) * n_chunks + ci];
  });
  std::vector<size_t> start(n_lanes + 1, 0);
  size_t placed = 0;
  for (size_t l = 0; l < n_lanes; ++l) {
    start[l] = placed;
    for (size_t ci = 0; ci < n_chunks; ++ci) {
      const uint32_t n = per[l * n_chunks + ci];
      per[l * n_chunks + ci] = static_cast<uint32_t>(placed);  // now: where the chunk's go
      placed += n;
    }
  }
  start[n_lanes] = placed;
  // The contributing segments, by lane, in sample order: (chunk, segment in the chunk).
  std::vector<std::pair<uint32_t, uint32_t>> order(placed);
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    for (size_t i = 0; i < c.segs.size(); ++i)
      if (flags[c.seg_start + i] & 3)
        order[per[lane_of(c, i) * n_chunks + ci]++] = {static_cast<uint32_t>(ci), static_cast<uint32_t>(i)};
  });
  tbb::parallel_for(size_t{0}, n_lanes, [&](size_t l) {
    MutationLane& lane = lanes[l];
    uint64_t added = 0;
    const bool own = my_lane(l);
    for (size_t at = start[l]; at < start[l + 1]; ++at) {
      const BatchChunk& c = chunks[order[at].first];
      const size_t i = order[at].second, k = c.seg_start + i;
      const Vec3 ends[2] = {c.segs.a(i), c.segs.b(i)};
      const uint32_t objs[2] = {c.segs.object_a[i], c.segs.object_b[i]};
      for (int e = 0; e < 2; ++e) {
        if (!((flags[k] >> e) & 1)) continue;
        ++added;
        if (!own) continue;
        const Candidate cand{ends[1 - e], ends[e], radius[k][1 - e], radius[k][e], objs[e]};
        lane.two_point.add(cand, lane_capacity);
        lane.silhouette.add(cand, lane_capacity);
      }
    }
    lane.count = std::min<uint64_t>(lane_capacity, lane.count + added);
  });
  stats.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
}

void AgvsSolver::Impl::sync() {
  if (!partitioned) return;
  // Each row from its owner: the others' copies of it are older subsets (bits) or must not be
  // counted twice (the filter's densities), so they are cleared before the reduction.
  const uint32_t n_cells = pvs.cell_count();
  const size_t words = pvs.words_per_row(), n_objects = pvs.object_count();
  std::vector<uint64_t>& bits = pvs.raw_bits();
  for (uint32_t c = 0; c < n_cells; ++c)
    if (!cluster::mine(c)) std::fill(bits.begin() + c * words, bits.begin() + (c + 1) * words, 0);
  cluster::bit_or(bits);
  pvs.recount();
  if (config.filter_statistics) {
    for (uint32_t c = 0; c < n_cells; ++c)
      if (!cluster::mine(c)) {
        cell_samples[c] = 0;
        std::fill(hit_counts.begin() + c * n_objects, hit_counts.begin() + (c + 1) * n_objects, 0);
      }
    cluster::sum(cell_samples);
    cluster::sum(hit_counts);
  }
  // The mutation lanes, each from its owner.
  std::vector<std::string> items(lanes.size());
  for (size_t l = 0; l < lanes.size(); ++l)
    if (my_lane(l)) {
      ByteWriter w;
      save_lane(w, lanes[l]);
      items[l] = w.take();
    }
  cluster::share(items, [&](size_t l) { return lane_owner(l); });
  for (size_t l = 0; l < lanes.size(); ++l)
    if (!my_lane(l)) {
      ByteReader r(items[l], "a rank's mutation candidates");
      lanes[l] = load_lane(r, items[l].size());
    }
  synced_entries = global_entries = pvs.entries();
  partitioned = false;
}

void AgvsSolver::Impl::batch(uint64_t index, uint32_t n) {
  double share[kDists];
  shares(share);
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto t = Clock::now();
  double lanes_before = stats.mutation_seconds;  // the lanes' time is counted apart
  BatchSamples s;
  draw_samples(index, n, share, s);
  stats.draw_seconds += since(t) - (stats.mutation_seconds - lanes_before);
  t = Clock::now();
  const size_t count = s.points.size();
  const std::vector<BatchChunk> chunks = cast_samples(s);
  stats.cast_seconds += since(t);
  t = Clock::now();
  lanes_before = stats.mutation_seconds;
  // Apply in sample order (contributions depend on what came before).
  BatchCounts counts;
  counts.rays[kSil] += s.discovery_rays;
  counts.camera_rays.assign(count, 0);
  counts.wrong_rays.assign(count, 0);
  counts.has_segment.assign(count, 0);
  apply_segments(s, chunks, counts);
  for (const BatchChunk& c : chunks) {
    stats.segments += c.segs.size();
    stats.pierced_cells += c.pierced;
  }
  // The estimator counts view space-direction samples (all of them for SGVS and REF).
  uint64_t vsd_rays = 0, vsd_contributing = 0;
  for (uint32_t k = s.first_of[kVsd]; k < s.end_of[kVsd]; ++k) {
    // No segment at all: both rays left the scene without a hit (the caster emits nothing
    // then), so the point is free and its camera sees nothing there: right pixels.
    if (!counts.has_segment[k]) counts.camera_rays[k] = config.method == AgvsMethod::kRef ? 1 : 2;
    vsd_rays += counts.camera_rays[k];
    vsd_contributing += counts.wrong_rays[k];
  }
  uint64_t samples_of[kDists];
  for (int d = 0; d < kDists; ++d) samples_of[d] = s.end_of[d] - s.first_of[d];
  update_weights(share, samples_of, counts.contribution, counts.rays);
  stats.samples += count;
  stats.batches += 1;
  stats.mutation_candidates = mutation_candidates();
  stats.camera_rays += vsd_rays;
  stats.wrong_camera_rays += vsd_contributing;
  update_estimate(vsd_rays, vsd_contributing);
  stats.apply_seconds += since(t) - (stats.mutation_seconds - lanes_before);
}

}  // namespace viewcells
