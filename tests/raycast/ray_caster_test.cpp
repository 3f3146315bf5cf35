// Embree against the brute-force oracle: random rays, and rays aimed exactly at edges and
// vertices where a leak would show.
#include <gtest/gtest.h>

#include <cmath>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/rng.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

Vec3 random_direction(Rng& rng) {
  const double phi = 2 * M_PI * rng.uniform(), z = 1 - 2 * rng.uniform(), r = std::sqrt(1 - z * z);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Compares two hits of the same ray. Distances agree to float precision of the scene size;
/// where two triangles lie at (nearly) the same distance either may be reported, so then only
/// the distance is compared.
void expect_same_hit(const Scene& scene, const Ray& ray, const Hit& embree, const Hit& oracle, double tol) {
  ASSERT_EQ(embree.hit(), oracle.hit()) << "origin " << ray.origin.x << "," << ray.origin.y << "," << ray.origin.z
                                         << " dir " << ray.dir.x << "," << ray.dir.y << "," << ray.dir.z
                                         << " oracle t " << oracle.t;
  if (!oracle.hit()) return;
  EXPECT_NEAR(embree.t, oracle.t, tol);
  if (embree.triangle != oracle.triangle) return;  // tie between coincident surfaces
  EXPECT_EQ(embree.object, oracle.object);
  EXPECT_EQ(embree.front, oracle.front);
}

TEST(RayCaster, EmbreeAgreesWithOracleOnRandomRays) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 3, 1});
  const auto embree = make_embree_caster(scene);
  const auto oracle = make_brute_force_caster(scene);
  Rng rng(42);
  const Box3& b = scene.bounds;
  int hits = 0, same_triangle = 0;
  for (int i = 0; i < 3000; ++i) {
    Ray ray;
    ray.origin = {rng.uniform(b.lo.x, b.hi.x), rng.uniform(b.lo.y, b.hi.y), rng.uniform(b.lo.z, b.hi.z)};
    ray.dir = random_direction(rng);
    const Hit e = embree->intersect(ray), o = oracle->intersect(ray);
    expect_same_hit(scene, ray, e, o, 1e-4);
    hits += o.hit();
    same_triangle += e.triangle == o.triangle;
  }
  EXPECT_GT(hits, 2900);  // the office is closed: almost every ray hits
  EXPECT_GT(same_triangle, 2950);
}

TEST(RayCaster, HitsCarryObjectAndFace) {
  const Scene scene = test::cube_grid(1);  // unit cube [0,1]^3
  for (const auto& caster : {make_embree_caster(scene), make_brute_force_caster(scene)}) {
    const Hit outside = caster->intersect(Ray{{0.5, 0.5, 5}, {0, 0, -1}});
    ASSERT_TRUE(outside.hit()) << caster->name();
    EXPECT_NEAR(outside.t, 4.0, 1e-6);
    EXPECT_TRUE(outside.front);
    EXPECT_EQ(outside.object, 0u);
    const Hit inside = caster->intersect(Ray{{0.5, 0.5, 0.5}, {0, 0, -1}});
    ASSERT_TRUE(inside.hit());
    EXPECT_NEAR(inside.t, 0.5, 1e-6);
    EXPECT_FALSE(inside.front) << "leaving a solid hits a back face";
    EXPECT_FALSE(caster->intersect(Ray{{0.5, 0.5, 5}, {0, 0, 1}}).hit());
    const Hit limited = caster->intersect(Ray{{0.5, 0.5, 5}, {0, 0, -1}, 0.0, 3.0});
    EXPECT_FALSE(limited.hit()) << "tfar limits the ray";
  }
}

/// Every ISA this CPU runs can be asked for by name, and casts the same closest objects as
/// the oracle on rays that graze nothing; unknown names and far-off rays are errors.
TEST(RayCaster, EveryIsaByNameAndInvalidRaysRefused) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const auto oracle = make_brute_force_caster(scene);
  const Vec3 c = scene.bounds.center();
  for (const std::string& isa : supported_embree_isas()) {
    EmbreeConfig config;
    config.isa = isa;
    const auto embree = make_embree_caster(scene, config);
    EXPECT_NE(embree->name().find(isa), std::string::npos) << embree->name();
    Rng rng(3);
    int same = 0;
    for (int i = 0; i < 500; ++i) {
      const Vec3 d = normalize(Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
      const Ray ray{c + Vec3{0.1, 0.2, 0.3}, d};
      same += embree->intersect(ray).object == oracle->intersect(ray).object;
    }
    EXPECT_GE(same, 495) << isa;  // a ray may graze an edge between two objects
  }
  EmbreeConfig bad;
  bad.isa = "avx9";
  EXPECT_THROW(make_embree_caster(scene, bad), Error);
  const auto embree = make_embree_caster(scene);
  EXPECT_THROW(embree->intersect(Ray{{1e19, 0, 0}, {1, 0, 0}}), Error);
  EXPECT_THROW(embree->intersect(Ray{c, {NAN, 0, 0}}), Error);
  EXPECT_THROW(embree->intersect(Ray{c, {1, 0, 0}, 2.0, 1.0}), Error);
}

/// Rays aimed exactly at shared edges and vertices, from directions where every triangle
/// meeting there faces the ray (so the surface continues on all sides and a miss is a leak),
/// must not slip through in robust mode. The oracle is watertight by construction.
TEST(RayCaster, NoLeaksThroughEdgesAndVertices) {
  const Scene scene = generate_scene({GeneratorKind::kRotatedOffice, 7, 2});
  EmbreeConfig robust;
  robust.robust = true;
  const auto embree = make_embree_caster(scene, robust);
  const auto oracle = make_brute_force_caster(scene);
  std::vector<std::vector<uint32_t>> incident(scene.vertices.size());
  for (uint32_t t = 0; t < scene.triangles.size(); ++t)
    for (uint32_t v : scene.triangles[t]) incident[v].push_back(t);
  auto faces_all = [&](const std::vector<uint32_t>& tris, const Vec3& d) {
    for (uint32_t t : tris)
      if (dot(normalize(scene.triangle_normal(t)), d) > -0.05) return false;
    return true;
  };
  Rng rng(7);
  int leaks_embree = 0, leaks_oracle = 0, rays = 0, edge_rays = 0;
  for (int i = 0; i < 20000 && rays < 2000; ++i) {
    const uint32_t t = static_cast<uint32_t>(rng.below(scene.triangles.size()));
    const auto& tri = scene.triangles[t];
    const uint32_t v0 = tri[0], v1 = tri[1];
    const bool at_vertex = i % 2;
    Vec3 target = scene.vertices[v0];
    std::vector<uint32_t> around = incident[v0];
    if (!at_vertex) {
      // Midpoint-ish of edge v0-v1 and the triangles sharing that edge.
      target = target + (scene.vertices[v1] - target) * (static_cast<double>(1 + rng.below(7)) / 8.0);
      around.clear();
      for (uint32_t u : incident[v0])
        for (uint32_t w : scene.triangles[u])
          if (w == v1) around.push_back(u);
      if (around.size() < 2) continue;  // a boundary edge: nothing on the other side
    }
    Vec3 d = -normalize(scene.triangle_normal(t));
    d = normalize(d + random_direction(rng) * 0.6);
    if (!faces_all(around, d)) continue;
    const Ray ray{target - d * 0.25, d};
    ++rays;
    edge_rays += !at_vertex;
    const Hit e = embree->intersect(ray), o = oracle->intersect(ray);
    leaks_embree += !e.hit();
    leaks_oracle += !o.hit();
    if (e.hit() && o.hit()) {
      EXPECT_NEAR(e.t, o.t, 1e-3);
    }
  }
  EXPECT_GT(rays, 1000);
  EXPECT_GT(edge_rays, 300);
  EXPECT_EQ(leaks_oracle, 0);
  EXPECT_EQ(leaks_embree, 0) << "Embree robust mode let rays slip through edges";
}

TEST(RayCaster, LargeCoordinatesKeepPrecision) {
  // The same cube translated by 1e5: Embree's local frame keeps float error far below 1 mm.
  Scene scene = test::cube_grid(2);
  translate(scene, {1e5, 1e5, 1e5});
  const auto embree = make_embree_caster(scene);
  const auto oracle = make_brute_force_caster(scene);
  Rng rng(3);
  for (int i = 0; i < 500; ++i) {
    Ray ray{{1e5 + rng.uniform(-1, 5), 1e5 + rng.uniform(-1, 5), 1e5 + rng.uniform(-1, 2)}, random_direction(rng)};
    expect_same_hit(scene, ray, embree->intersect(ray), oracle->intersect(ray), 1e-4);
  }
}

TEST(RayCaster, BatchesMatchSingleRays) {
  const Scene scene = generate_scene({GeneratorKind::kCity, 5, 1});
  const auto embree = make_embree_caster(scene);
  Rng rng(9);
  std::vector<Ray> rays(1000);
  for (Ray& r : rays) {
    r.origin = {rng.uniform(scene.bounds.lo.x, scene.bounds.hi.x), rng.uniform(scene.bounds.lo.y, scene.bounds.hi.y),
                rng.uniform(0, 30)};
    r.dir = random_direction(rng);
  }
  std::vector<Hit> hits(rays.size());
  embree->intersect(rays, hits);
  for (size_t i = 0; i < rays.size(); ++i) {
    const Hit single = embree->intersect(rays[i]);
    EXPECT_EQ(single.triangle, hits[i].triangle);
    EXPECT_EQ(single.t, hits[i].t);
  }
}

TEST(RayCaster, EmptySceneIsAnError) {
  Scene empty;
  EXPECT_THROW(make_embree_caster(empty), Error);
}

}  // namespace
}  // namespace viewcells
