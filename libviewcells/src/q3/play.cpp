/// Where players stand on a Quake 3 map: the play space (reachable leaves near walkable floors) and
/// player cameras.
#include "viewcells/q3/play.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <span>

#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/core/rng.h"
#include "viewcells/q3/view_space.h"
#include "viewcells/viewspace/floor_space.h"

namespace viewcells {

std::vector<bool> q3_reachable_leaves(const Q3Map& map, size_t* spawn_points) {
  const Box3 box = q3_view_box(map);
  const Subdivision s = q3_subdivision(map, box);
  const int32_t inner = static_cast<int32_t>(map.nodes.size());
  std::vector<int32_t> open;
  for (size_t l = 0; l < map.leaves.size(); ++l)
    if (map.leaves[l].cluster >= 0 && !s.cells[inner + l].empty()) open.push_back(inner + static_cast<int32_t>(l));
  std::vector<std::vector<int32_t>> next(map.leaves.size());
  for (const LeafAdjacency& a : leaf_adjacency(s, open)) {
    next[a.a - inner].push_back(a.b - inner);
    next[a.b - inner].push_back(a.a - inner);
  }
  std::vector<bool> reached(map.leaves.size(), false);
  std::vector<int32_t> stack;
  const std::vector<Vec3> spawns = q3_spawn_points(map);
  if (spawn_points) *spawn_points = spawns.size();
  for (const Vec3& p : spawns) {
    // A spawn origin stands 24 units above the floor; one placed a little low still finds its leaf.
    for (double up : {0.0, 16.0, 32.0}) {
      const int32_t l = map.leaf_at(p + Vec3{0, 0, up});
      if (map.leaves[l].cluster < 0) continue;
      if (!reached[l]) stack.push_back(l);
      reached[l] = true;
      break;
    }
  }
  if (spawns.empty())
    for (int32_t n : open) {
      reached[n - inner] = true;
      stack.push_back(n - inner);
    }
  while (!stack.empty()) {
    const int32_t l = stack.back();
    stack.pop_back();
    for (int32_t m : next[l])
      if (!reached[m]) {
        reached[m] = true;
        stack.push_back(m);
      }
  }
  return reached;
}

PlaySpace q3_play_space(const Q3Map& map, const Scene& scene, const RayCaster& caster, const PlaySpaceConfig& config) {
  if (config.columns == 0 || !(config.reach > 0) || !(config.step > 0) || !(config.walk_normal > 0 && config.walk_normal <= 1))
    throw Error("play space: columns, reach, step and walkable normal must be positive (the normal at most 1)");
  if (!(config.reach / config.step <= 1e6)) throw Error("play space: reach / step exceeds a million points a column");
  PlaySpace out;
  const std::vector<bool> reachable = q3_reachable_leaves(map);
  const WalkableFloors floors(scene, config.walk_normal);
  if (floors.empty()) throw Error(map.path, 0, "play space: the map has no walkable surface");
  // Marks are only ever set, so the columns may mark them in any order: the same leaves for
  // any number of threads.
  std::vector<std::atomic<uint8_t>> marked(map.leaves.size());
  const Vec3 up{0, 0, 1};
  constexpr double kLift = 0.25;  // off the floor, so the floor itself is not what the ray meets
  // A column's points, every `step` units from kLift up to `reach`.
  std::vector<double> heights;
  for (double h = kLift; h < config.reach; h += config.step) heights.push_back(h);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, config.columns, 1024), [&](const tbb::blocked_range<uint32_t>& r) {
    std::vector<int32_t> leaves;
    for (uint32_t i = r.begin(); i < r.end(); ++i) {
      Rng rng(config.seed, (uint64_t{92} << 40) | i);
      const double pick = rng.uniform(), u = rng.uniform(), v = rng.uniform();
      const Vec3 f = floors.point(scene, pick, u, v);
      const Hit hit = caster.intersect(Ray{f + up * kLift, up, 0, config.reach - kLift});
      const double top = hit.hit() ? kLift + hit.t : config.reach;
      const auto end = std::lower_bound(heights.begin(), heights.end(), top);
      map.column_leaves(f, std::span<const double>(heights.data(), end - heights.begin()), leaves);
      for (const int32_t l : leaves)
        if (reachable[l] && !marked[l].load(std::memory_order_relaxed)) marked[l].store(1, std::memory_order_relaxed);
    }
  });
  out.leaves.assign(map.leaves.size(), false);
  const Subdivision s = q3_subdivision(map, q3_view_box(map));
  const size_t inner = map.nodes.size();
  for (size_t l = 0; l < map.leaves.size(); ++l) {
    if (map.leaves[l].cluster < 0) continue;
    const double volume = s.nodes[inner + l].volume;
    ++out.open_leaves;
    out.open_volume += volume;
    if (!marked[l].load()) continue;
    out.leaves[l] = true;
    ++out.play_leaves;
    out.play_volume += volume;
  }
  out.rule = "the non-solid leaves reachable from the spawn points that hold a point at most " + fmt(config.reach, 0) +
             " units above a walkable floor (normal z >= " + fmt(config.walk_normal, 2) + ") with free space up to it (" +
             std::to_string(out.play_leaves) + " of " + std::to_string(out.open_leaves) + " leaves, " +
             fmt(100 * out.play_volume / std::max(out.open_volume, 1e-300), 1) + "% of the non-solid volume; " +
             std::to_string(config.columns) + " columns)";
  return out;
}

PlayCameras q3_play_cameras(const Q3Map& map, const Scene& scene, const RayCaster& caster,
                            const PlayCameraConfig& config) {
  if (config.count == 0) throw Error("play cameras: the count must be positive");
  if (!(config.eye_height > 0 && config.player_height >= config.eye_height &&
        config.walk_normal > 0 && config.walk_normal <= 1 && config.max_pitch_degrees >= 0 &&
        config.max_pitch_degrees < 90))
    throw Error("play cameras: eye height, player height, walkable normal or pitch out of range");
  PlayCameras out;
  const std::vector<bool> reachable = q3_reachable_leaves(map, &out.spawn_points);
  for (size_t l = 0; l < map.leaves.size(); ++l) {
    out.open_leaves += map.leaves[l].cluster >= 0;
    out.reachable_leaves += reachable[l];
  }
  const auto in_play_space = [&](const Vec3& p) {
    const int32_t l = map.leaf_at(p);
    return reachable[l] && q3_in_view_space(map, p);
  };
  const WalkableFloors floors(scene, config.walk_normal);
  if (floors.empty()) throw Error(map.path, 0, "play cameras: the map has no walkable surface");
  const Vec3 up{0, 0, 1};
  const double pitch = config.max_pitch_degrees * std::numbers::pi / 180;
  Rng rng(config.seed, 91);
  // Floors under other floors, in solid space or out of reach are drawn and dropped; the bound
  // only stops maps that have (nearly) no floor a player can reach.
  const uint64_t max_draws = 20000 + uint64_t{1000} * config.count;
  while (out.cameras.size() < config.count) {
    if (out.points_drawn >= max_draws)
      throw Error(map.path, 0,
                  "play cameras: only " + std::to_string(out.cameras.size()) + " of " + std::to_string(config.count) +
                      " found in " + std::to_string(out.points_drawn) +
                      " points of walkable surfaces (none reachable from the spawn points?)");
    ++out.points_drawn;
    const double pick = rng.uniform(), su = rng.uniform(), v = rng.uniform();
    const double yaw = 2 * std::numbers::pi * rng.uniform(), look = pitch * (2 * rng.uniform() - 1);
    const Vec3 f = floors.point(scene, pick, su, v);
    // Free space for a player: nothing above the floor up to the player's height.
    if (caster.intersect(Ray{f + up * 0.25, up, 0, config.player_height - 0.25}).hit()) continue;
    const Vec3 eye = f + up * config.eye_height;
    if (!in_play_space(eye)) continue;
    out.cameras.push_back(camera_looking(eye, yaw, look));
    out.leaves.push_back(map.leaf_at(eye));
  }
  out.rule = "player eyes " + fmt(config.eye_height, 0) + " units above walkable floors (uniform by area; normal z >= " +
             fmt(config.walk_normal, 2) + ", " + fmt(config.player_height, 0) +
             " units free above) in non-solid leaves reachable from " +
             (out.spawn_points ? std::to_string(out.spawn_points) + " spawn points" : std::string("anywhere (no spawn points)")) +
             " (" + std::to_string(out.reachable_leaves) + " of " + std::to_string(out.open_leaves) +
             " non-solid leaves); yaw uniform, pitch uniform within +-" + fmt(config.max_pitch_degrees, 0) +
             " degrees, no roll";
  return out;
}

PlaySpaceOverlap q3_play_space_overlap(const Q3Map& map, const Scene& scene, const RayCaster& caster,
                                       const PlaySpace& play, const FloorSpace& found, double found_scale,
                                       uint64_t points, uint64_t seed, int image_width) {
  if (!(found_scale > 0) || points == 0) throw Error("play space overlap: the scale and the points must be positive");
  if (image_width < 0 || image_width > 8192) throw Error("play space overlap: the picture is 1 to 8192 pixels wide");
  const FloorSpaceConfig& u = found.units();
  const double lo = u.eye_low / found_scale, hi = u.eye_high / found_scale;  // in map units
  const Vec3 down{0, 0, -1};
  const auto in_map = [&](const Vec3& p) {
    if (!play.leaves[map.leaf_at(p)] || !q3_in_view_space(map, p)) return false;
    const Hit hit = caster.intersect(Ray{p, down, 0, hi});
    return hit.hit() && hit.t >= lo && walkable_floor_hit(scene, hit, u.walk_normal);
  };
  const auto in_found = [&](const Vec3& p) { return found.contains(p * found_scale); };
  Box3 box = q3_view_box(map);
  if (!found.empty()) {
    box.extend(found.box().lo * (1 / found_scale));
    box.extend(found.box().hi * (1 / found_scale));
  }
  PlaySpaceOverlap out;
  out.points = points;
  out.box_volume = box.volume();
  // Counts per block of points, summed in block order: the same for any number of threads.
  constexpr uint64_t kBlock = 4096;
  const uint64_t blocks = (points + kBlock - 1) / kBlock;
  std::vector<std::array<uint64_t, 3>> counts(blocks, {0, 0, 0});
  tbb::parallel_for(tbb::blocked_range<uint64_t>(0, blocks), [&](const tbb::blocked_range<uint64_t>& r) {
    for (uint64_t k = r.begin(); k < r.end(); ++k) {
      Rng rng(seed, (uint64_t{95} << 40) | k);
      for (uint64_t i = k * kBlock; i < std::min(points, (k + 1) * kBlock); ++i) {
        const Vec3 p{rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y), rng.uniform(box.lo.z, box.hi.z)};
        const bool a = in_map(p), b = in_found(p);
        counts[k][0] += a;
        counts[k][1] += b;
        counts[k][2] += a && b;
      }
    }
  });
  std::array<uint64_t, 3> sum{0, 0, 0};
  for (const auto& c : counts)
    for (int j = 0; j < 3; ++j) sum[j] += c[j];
  const double per_point = out.box_volume / static_cast<double>(points);
  out.map_volume = sum[0] * per_point;
  out.found_volume = sum[1] * per_point;
  out.both_volume = sum[2] * per_point;
  if (image_width == 0) return out;
  const Vec3 e = box.extent();
  const double scale = image_width / e.x;
  out.width = image_width;
  out.height = std::max(1, static_cast<int>(std::ceil(e.y * scale)));
  out.rgb.assign(static_cast<size_t>(out.width) * out.height * 3, 255);
  tbb::parallel_for(tbb::blocked_range<int>(0, out.height), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y < r.end(); ++y)
      for (int x = 0; x < out.width; ++x) {
        const double top = box.hi.z + 1;
        const Vec3 o{box.lo.x + (x + 0.5) / scale, box.hi.y - (y + 0.5) / scale, top};
        bool floors = false, both = false, map_only = false, found_only = false;
        double t = 0;
        for (int k = 0; k < 64; ++k) {
          const Hit hit = caster.intersect(Ray{o, down, t, top - box.lo.z + 1});
          if (!hit.hit()) break;
          t = hit.t + 1e-3;
          if (!walkable_floor_hit(scene, hit, u.walk_normal)) continue;
          floors = true;
          const Vec3 p = o + down * hit.t + Vec3{0, 0, 0.5 * (lo + hi)};
          const bool a = in_map(p), b = in_found(p);
          both |= a && b;
          map_only |= a && !b;
          found_only |= b && !a;
        }
        unsigned char* px = &out.rgb[3 * (static_cast<size_t>(y) * out.width + x)];
        const unsigned char colour[3] = {static_cast<unsigned char>(map_only ? 220 : found_only ? 40 : both ? 60 : floors ? 225 : 255),
                                         static_cast<unsigned char>(map_only ? 40 : found_only ? 90 : both ? 170 : floors ? 225 : 255),
                                         static_cast<unsigned char>(map_only ? 40 : found_only ? 230 : both ? 60 : floors ? 225 : 255)};
        std::copy(colour, colour + 3, px);
      }
  });
  return out;
}

}  // namespace viewcells
