#include "viewcells/q3/play.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/q3/view_space.h"

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
  // The walkable surfaces, by area: rendered occluders facing up (sky and brush hulls are not
  // rendered, water does not stop rays).
  std::vector<std::pair<double, uint32_t>> floors;
  double total = 0;
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
    const ObjectInfo& o = scene.objects[scene.triangle_object[t]];
    if (!o.rendered || !o.occluder) continue;
    const Vec3 n = scene.triangle_normal(t);
    const double twice_area = length(n);
    if (!(twice_area > 0) || n.z < config.walk_normal * twice_area) continue;
    total += 0.5 * twice_area;
    floors.emplace_back(total, t);
  }
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
    const double pick = rng.uniform() * total, su = std::sqrt(rng.uniform()), v = rng.uniform();
    const double yaw = 2 * std::numbers::pi * rng.uniform(), look = pitch * (2 * rng.uniform() - 1);
    const auto it = std::lower_bound(floors.begin(), floors.end(), std::make_pair(pick, uint32_t{0}));
    const auto& tri = scene.triangles[(it == floors.end() ? floors.back() : *it).second];
    const Vec3 f = scene.vertices[tri[0]] * (1 - su) + scene.vertices[tri[1]] * (su * (1 - v)) +
                   scene.vertices[tri[2]] * (su * v);
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

}  // namespace viewcells
