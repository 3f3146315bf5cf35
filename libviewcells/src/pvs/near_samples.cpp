// Near-object samples (near_samples.h): test the neighbours of what each view cell sees.
#include "viewcells/pvs/near_samples.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iterator>
#include <numeric>

#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells {

std::vector<std::vector<uint32_t>> object_neighbours(const Scene& scene, double distance) {
  const uint32_t n = scene.object_count();
  std::vector<uint32_t> order;
  for (uint32_t o = 0; o < n; ++o)
    if (scene.objects[o].rendered && !scene.objects[o].bounds.empty()) order.push_back(o);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const double la = scene.objects[a].bounds.lo.x, lb = scene.objects[b].bounds.lo.x;
    return la < lb || (la == lb && a < b);
  });
  std::vector<std::vector<uint32_t>> out(n);
  for (size_t i = 0; i < order.size(); ++i) {
    const Box3& a = scene.objects[order[i]].bounds;
    for (size_t j = i + 1; j < order.size(); ++j) {
      const Box3& b = scene.objects[order[j]].bounds;
      if (b.lo.x > a.hi.x + distance) break;  // sorted by low x: none further on is nearer in x
      if (b.lo.y > a.hi.y + distance || a.lo.y > b.hi.y + distance || b.lo.z > a.hi.z + distance ||
          a.lo.z > b.hi.z + distance)
        continue;
      out[order[i]].push_back(order[j]);
      out[order[j]].push_back(order[i]);
    }
  }
  for (auto& l : out) std::sort(l.begin(), l.end());
  return out;
}

namespace {

/// Uniform points on an object's surface: its triangles with their cumulative areas.
struct Surface {
  std::vector<uint32_t> triangles;
  std::vector<double> cumulative;  ///< running sum of the areas

  Vec3 point(const Scene& scene, Rng& rng) const {
    const double x = rng.uniform() * cumulative.back();
    const size_t k = std::min<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), x) - cumulative.begin(),
                                      triangles.size() - 1);
    const auto& t = scene.triangles[triangles[k]];
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    const Vec3 &a = scene.vertices[t[0]], &b = scene.vertices[t[1]], &c = scene.vertices[t[2]];
    return a + (b - a) * u + (c - a) * v;
  }
};

std::vector<Surface> surfaces(const Scene& scene) {
  std::vector<Surface> out(scene.object_count());
  for (uint32_t t = 0; t < scene.triangle_count(); ++t) {
    const auto& tri = scene.triangles[t];
    const double area =
        0.5 * length(cross(scene.vertices[tri[1]] - scene.vertices[tri[0]], scene.vertices[tri[2]] - scene.vertices[tri[0]]));
    if (!(area > 0)) continue;
    Surface& s = out[scene.triangle_object[t]];
    s.triangles.push_back(t);
    s.cumulative.push_back((s.cumulative.empty() ? 0.0 : s.cumulative.back()) + area);
  }
  return out;
}

}  // namespace

NearSampleStats add_near_samples(const Scene& scene, const RayCaster& caster,
                                 const std::vector<std::vector<Vec3>>& eyes, const NearSampleConfig& config,
                                 std::vector<std::vector<uint32_t>>& lists) {
  if (eyes.size() != lists.size()) throw Error("add_near_samples: one set of viewpoints per view cell");
  NearSampleStats stats;
  stats.distance = config.distance > 0 ? config.distance : 1e-3 * scene.bounds.diagonal();
  if (config.rays_per_object == 0 || config.rounds == 0) return stats;
  const std::vector<std::vector<uint32_t>> near = object_neighbours(scene, stats.distance);
  const std::vector<Surface> surface = surfaces(scene);
  const size_t cells = lists.size();
  // Per cell, the objects the last round added (the first round: its whole PVS): their
  // neighbours are the next candidates.
  std::vector<std::vector<uint32_t>> fresh = lists;
  uint64_t rays_left = config.max_rays;
  const auto start = std::chrono::steady_clock::now();
  std::atomic<bool> out_of_time{false};
  auto time_is_up = [&] {
    if (config.max_seconds <= 0) return false;
    if (!out_of_time.load(std::memory_order_relaxed) &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > config.max_seconds)
      out_of_time = true;
    return out_of_time.load(std::memory_order_relaxed);
  };
  for (uint32_t round = 0; round < config.rounds && !time_is_up(); ++round) {
    // Each cell's candidates: the neighbours of what it gained last that it lacks.
    std::vector<std::vector<uint32_t>> missing(cells);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells, 1), [&](const tbb::blocked_range<size_t>& range) {
      std::vector<uint32_t> candidates;
      for (size_t c = range.begin(); c < range.end(); ++c) {
        if (eyes[c].empty() || fresh[c].empty()) continue;
        candidates.clear();
        for (uint32_t o : fresh[c]) candidates.insert(candidates.end(), near[o].begin(), near[o].end());
        std::sort(candidates.begin(), candidates.end());
        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
        std::set_difference(candidates.begin(), candidates.end(), lists[c].begin(), lists[c].end(),
                            std::back_inserter(missing[c]));
        missing[c].erase(std::remove_if(missing[c].begin(), missing[c].end(),
                                        [&](uint32_t o) { return surface[o].triangles.empty(); }),
                         missing[c].end());
      }
    });
    uint64_t pairs = 0;
    for (const auto& m : missing) pairs += m.size();
    if (pairs == 0) break;
    // Rays per pair: as asked, fewer (in whole packets of 16, at least one) where the candidates
    // would take more than the rays left; the same for any number of threads.
    uint64_t k = config.rays_per_object;
    if (pairs * k > rays_left) k = std::max<uint64_t>(16, rays_left / pairs / 16 * 16);
    k = std::min<uint64_t>(k, config.rays_per_object);
    if (pairs * k > rays_left) break;  // not even a packet a pair is left
    rays_left -= pairs * k;
    stats.rays_by_round.push_back(k);
    const uint32_t per = static_cast<uint32_t>(k);
    std::vector<std::vector<uint32_t>> found(cells);
    std::vector<uint64_t> tested(cells, 0);
    Progress progress("near-object samples, round " + std::to_string(round + 1), cells);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells, 1), [&](const tbb::blocked_range<size_t>& range) {
      std::vector<Ray> rays(per);
      std::vector<Hit> hits(per);
      std::vector<Vec3> targets(per);
      for (size_t c = range.begin(); c < range.end(); ++c) {
        throw_if_interrupted("near-object samples");
        progress.advance();
        if (time_is_up()) continue;
        Rng rng(config.seed ^ 0x6e65'6172'0000'0000ULL, (uint64_t{round} << 40) ^ c);
        for (uint32_t o : missing[c]) {
          ++tested[c];
          // Sixteen rays from one eye to sixteen points of the object run side by side: Embree
          // casts them as a coherent packet (intersect_coherent).
          const Vec3* eye = nullptr;
          for (uint32_t r = 0; r < per; ++r) {
            if (r % 16 == 0) eye = &eyes[c][rng.below(eyes[c].size())];
            targets[r] = surface[o].point(scene, rng);
            rays[r] = Ray{*eye, targets[r] - *eye, 0.0, 1.0 + 1e-6};
            if (!(dot(rays[r].dir, rays[r].dir) > 0)) rays[r] = Ray{*eye, {1, 0, 0}, 0.0, 0.0};  // an eye on the object
          }
          caster.intersect_coherent(rays, hits);
          const bool occluder = scene.objects[o].occluder;
          for (uint32_t r = 0; r < per; ++r) {
            // An occluder is seen when the ray's first hit is on it; what one sees through (not
            // hit by any ray) when nothing stops the ray before the point on it.
            const bool seen = occluder ? hits[r].hit() && hits[r].object == o : !(hits[r].hit() && hits[r].t < 1 - 1e-6);
            if (seen) {
              found[c].push_back(o);
              break;
            }
          }
        }
      }
    });
    progress.finish();
    uint64_t added = 0;
    for (size_t c = 0; c < cells; ++c) {
      stats.tested += tested[c];
      stats.rays += tested[c] * per;
      std::vector<uint32_t> merged;
      std::set_union(lists[c].begin(), lists[c].end(), found[c].begin(), found[c].end(), std::back_inserter(merged));
      added += merged.size() - lists[c].size();
      lists[c].swap(merged);
      fresh[c] = std::move(found[c]);
    }
    stats.added += added;
    stats.added_by_round.push_back(added);
    if (added == 0) break;
  }
  stats.stopped_by_time = out_of_time;
  return stats;
}

}  // namespace viewcells
