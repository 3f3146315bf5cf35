// Embree robust versus fast mode: rays that slip through shared edges and vertices, counted
// against the watertight brute-force caster, and the speed of each mode.
// Usage: viewcells_leaks LEAK_SCENE SPEED_SCENE RAYS SPEED_RAYS OUT.json
// LEAK_SCENE must be small (the oracle tests every triangle for every ray).
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <map>
#include <iostream>

#include "viewcells/core/error.h"
#include "viewcells/core/rng.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/q3/bsp_file.h"

using namespace viewcells;

namespace {

Vec3 random_direction(Rng& rng) {
  const double z = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * 3.14159265358979323846 * rng.uniform();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Rays of one kind: "random" (uniform in the bounds), "edge" (aimed at a point of an edge
/// shared by two triangles, from the side both face), "vertex" (aimed at a vertex, from a
/// side every triangle around it faces). Such a ray enters the surface there, so it must hit
/// it: a miss is a leak, not a graze of a silhouette (which may rightly go either way).
std::vector<Ray> make_rays(const Scene& scene, const std::string& kind, size_t n, uint64_t seed) {
  Rng rng(seed, kind == "random" ? 1 : (kind == "edge" ? 2 : 3));
  const Box3 b = scene.bounds;
  const double reach = 0.25 * b.diagonal();
  std::vector<Ray> rays;
  if (kind == "random") {
    while (rays.size() < n) {
      const Vec3 o{b.lo.x + rng.uniform() * (b.hi.x - b.lo.x), b.lo.y + rng.uniform() * (b.hi.y - b.lo.y),
                   b.lo.z + rng.uniform() * (b.hi.z - b.lo.z)};
      rays.push_back({o, random_direction(rng)});
    }
    return rays;
  }
  // Triangles around each edge and each vertex.
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edges;
  std::vector<std::vector<uint32_t>> around(scene.vertices.size());
  for (uint32_t t = 0; t < scene.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = scene.triangles[t][k], v = scene.triangles[t][(k + 1) % 3];
      edges[{std::min(u, v), std::max(u, v)}].push_back(t);
      around[u].push_back(t);
    }
  std::vector<std::pair<uint32_t, uint32_t>> shared;
  for (const auto& [e, tris] : edges)
    if (tris.size() == 2) shared.push_back(e);
  if (shared.empty()) throw Error("the scene has no edges shared by two triangles");
  size_t attempts = 0;
  while (rays.size() < n && attempts++ < 100 * n) {
    std::vector<uint32_t> faces;
    Vec3 target;
    if (kind == "edge") {
      const auto e = shared[rng.below(shared.size())];
      faces = edges[e];
      const Vec3 p = scene.vertices[e.first], q = scene.vertices[e.second];
      target = p + (q - p) * (0.05 + 0.9 * rng.uniform());
    } else {
      const uint32_t v = static_cast<uint32_t>(rng.below(scene.vertices.size()));
      if (around[v].size() < 3) continue;
      faces = around[v];
      target = scene.vertices[v];
    }
    const Vec3 d = random_direction(rng);
    bool facing = true;
    for (uint32_t t : faces) facing = facing && dot(scene.triangle_normal(t), d) < 0;
    if (!facing) continue;
    rays.push_back({target - d * (reach * (0.05 + rng.uniform())), d});
  }
  return rays;
}

}  // namespace

int main(int argc, char** argv) {
  viewcells::register_q3_map_format();
  if (argc != 6) {
    std::cerr << "usage: viewcells_leaks LEAK_SCENE SPEED_SCENE RAYS SPEED_RAYS OUT.json\n";
    return 2;
  }
  try {
    const Scene leak_scene = load_scene(argv[1]);
    const Scene speed_scene = load_scene(argv[2]);
    const size_t n = std::stoul(argv[3]), speed_n = std::stoul(argv[4]);
    const auto oracle = make_brute_force_caster(leak_scene);
    nlohmann::json out;
    out["leak_scene"] = {{"file", argv[1]}, {"triangles", leak_scene.triangle_count()}};
    out["speed_scene"] = {{"file", argv[2]}, {"triangles", speed_scene.triangle_count()}};
    const double tol_abs = 1e-6 * leak_scene.bounds.diagonal();
    for (const std::string kind : {"random", "edge", "vertex"}) {
      const std::vector<Ray> rays = make_rays(leak_scene, kind, n, 7);
      std::vector<Hit> want(rays.size()), got(rays.size());
      oracle->intersect(rays, want);
      for (const bool robust : {true, false}) {
        const auto embree = make_embree_caster(leak_scene, EmbreeConfig{robust, true});
        embree->intersect(rays, got);
        size_t leaks = 0, oracle_hits = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
          if (!want[i].hit()) continue;
          ++oracle_hits;
          // Passed through: Embree sees nothing, or something clearly beyond the oracle's hit.
          if (!got[i].hit() || got[i].t > want[i].t * (1 + 1e-4) + tol_abs) ++leaks;
        }
        out["leaks"][robust ? "robust" : "fast"][kind] = {
            {"rays", rays.size()}, {"oracle_hits", oracle_hits}, {"leaks", leaks}};
      }
    }
    for (const bool robust : {true, false}) {
      const auto speed = make_embree_caster(speed_scene, EmbreeConfig{robust, true});
      const std::vector<Ray> rays = make_rays(speed_scene, "random", speed_n, 11);
      double best = 1e300;
      for (int rep = 0; rep < 3; ++rep) best = std::min(best, speed->time_raw(rays));
      out["speed"][robust ? "robust" : "fast"] = {
          {"rays", rays.size()}, {"seconds", best}, {"rays_per_second", rays.size() / best}};
    }
    std::ofstream(argv[5]) << out.dump(2) << '\n';
    std::cout << out.dump(2) << '\n';
  } catch (const Error& e) {
    std::cerr << "viewcells_leaks: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
