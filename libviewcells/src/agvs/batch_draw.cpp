// AGVS paper 4.1 and 4.3: a batch's samples drawn, from its own random stream: the mixture's
// share of each distribution, the mutations lane by lane from their candidates, and the
// silhouette searches (batch.h).
#include "batch.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <chrono>
#include <cmath>
#include <span>
#include <tuple>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/ranks.h"

namespace viewcells {

namespace {

struct SilhouetteJob {
  Candidate candidate;
  double u[2] = {0, 0};
  int n = 0;
  Vec3 points[2], dirs[2];
  uint64_t rays = 0;
};

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
  if (ranks::size() > 1) {
    std::vector<std::string> items(n_lanes);
    for (size_t l = 0; l < n_lanes; ++l)
      if (my_lane(l)) {
        ByteWriter w;
        w.put(counts[l]);
        items[l] = w.take();
      }
    ranks::share(items, [&](size_t l) { return lane_owner(l); });
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
    s.end_of[kVsd] = s.count = n;
    return;
  }
  const uint32_t failed = draw_mutations(index, want, s);
  // The stationary distributions: ranges of Halton indices, as many as should give the wanted
  // samples, in chunks of about kChunkSamples samples each. Their samples are drawn where they
  // are cast (cast_samples()), so no rank draws another's.
  constexpr uint64_t kMaxTries = 10000;  // a view space of nearly no volume must not stall a batch
  for (int d : kOrder) {
    if (d == kSil || d == kTpm) continue;
    const uint64_t wanted = want[d] + (d == kVsd ? failed : 0);
    if (wanted == 0) continue;
    const double yield = sample_share(d);
    const uint64_t indices = std::min<uint64_t>(static_cast<uint64_t>(std::ceil(static_cast<double>(wanted) / yield)), wanted * kMaxTries);
    const uint64_t per_chunk =
        std::min<uint64_t>(static_cast<uint64_t>(std::ceil(kChunkSamples / yield)), kChunkSamples * kMaxTries);
    for (uint64_t f = 0; f < indices; f += per_chunk)
      s.stationary.push_back({d, halton_index[d] + f, static_cast<uint32_t>(std::min(per_chunk, indices - f))});
    halton_index[d] += indices;
  }
}

}  // namespace viewcells
