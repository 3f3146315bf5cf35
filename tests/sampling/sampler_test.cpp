// Invariants of visibility segments (paper section 4.1), checked against the brute-force
// oracle: endpoints in the view box, the object recorded at each end is what a ray from the
// segment sees there, nothing blocks the segment, and with empty space detection no segment
// runs inside a solid.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

/// Parity test: is p inside the closed object `obj`? Casts along a fixed generic direction.
bool inside_object(const Scene& scene, uint32_t obj, const Vec3& p) {
  const Vec3 d = normalize(Vec3{0.5377, 0.1234, 0.8339});
  int crossings = 0;
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
    if (scene.triangle_object[t] != obj) continue;
    const auto& tri = scene.triangles[t];
    const Vec3 a = scene.vertices[tri[0]], e1 = scene.vertices[tri[1]] - a, e2 = scene.vertices[tri[2]] - a;
    const Vec3 h = cross(d, e2);
    const double det = dot(e1, h);
    if (std::abs(det) < 1e-15) continue;
    const Vec3 s = p - a;
    const double u = dot(s, h) / det;
    if (u < 0 || u > 1) continue;
    const Vec3 q = cross(s, e1);
    const double v = dot(d, q) / det;
    if (v < 0 || u + v > 1) continue;
    if (dot(e2, q) / det > 0) ++crossings;
  }
  return crossings % 2 == 1;
}

bool inside_any_solid(const Scene& scene, const Vec3& p) {
  for (uint32_t o = 0; o < scene.objects.size(); ++o)
    if (scene.objects[o].solid() && scene.objects[o].bounds.contains(p) && inside_object(scene, o, p)) return true;
  return false;
}

struct Violations {
  int outside_box = 0, wrong_object = 0, blocked = 0, inside_solid = 0, checked = 0;
  std::string examples;  ///< the first few violations, for the failure message
};

/// Checks up to `limit` segments; `tol` is an absolute distance tolerance.
Violations check_segments(const Scene& scene, const SegmentSet& segs, size_t limit, double tol,
                          bool check_solids) {
  const auto oracle = make_brute_force_caster(scene);
  Violations v;
  const size_t step = std::max<size_t>(1, segs.size() / limit);
  for (size_t i = 0; i < segs.size(); i += step) {
    ++v.checked;
    const Vec3 a = segs.a(i), b = segs.b(i);
    if (!segs.view_box.contains(a) || !segs.view_box.contains(b)) ++v.outside_box;
    const Vec3 m = (a + b) * 0.5;
    const double half = length(b - a) * 0.5;
    for (int end = 0; end < 2; ++end) {
      const Vec3 target = end ? b : a;
      const uint32_t obj = end ? segs.object_b[i] : segs.object_a[i];
      if (half < tol) continue;
      const Hit h = oracle->intersect(Ray{m, (target - m) / half});
      if (h.hit() && h.t < half - tol) {
        ++v.blocked;  // something lies between the midpoint and this end
      } else if (obj != kNoObject && !(h.hit() && std::abs(h.t - half) <= tol && h.object == obj)) {
        ++v.wrong_object;
        if (v.wrong_object < 4)
          v.examples += "segment " + std::to_string(i) + " end " + std::to_string(end) + " names object " +
                        std::to_string(obj) + ", the oracle sees " + std::to_string(h.object) + " at t " +
                        std::to_string(h.t) + " of " + std::to_string(half) + "\n";
      }
    }
    if (check_solids && inside_any_solid(scene, m)) {
      if (v.inside_solid < 4)
        v.examples += "segment " + std::to_string(i) + " runs inside a solid, midpoint " + std::to_string(m.x) + " " +
                      std::to_string(m.y) + " " + std::to_string(m.z) + "\n";
      ++v.inside_solid;
    }
  }
  return v;
}

SamplingResult sample(const Scene& scene, uint64_t samples, uint64_t seed,
                      EmptySpaceMode esd = EmptySpaceMode::kAuto, Box3 box = {}) {
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = samples;
  config.seed = seed;
  config.empty_space = esd;
  config.view_box = box;
  config.show_progress = false;
  return sample_segments(scene, *caster, config);
}

TEST(Sampler, SegmentsSatisfyInvariantsInTheOffice) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const SamplingResult r = sample(scene, 20000, 1);
  const SamplingStats& st = r.stats;
  EXPECT_TRUE(st.empty_space.enabled) << "generated scenes are solid";
  EXPECT_EQ(st.valid_segments + st.missed_both + st.stuck_in_solid + st.outside_view_box,
            st.samples + st.two_sided_samples);
  EXPECT_GT(st.two_sided_samples, 0u);
  EXPECT_EQ(st.rays, 2 * st.samples + st.recast_rays);
  EXPECT_GT(st.recast_rays, 0u) << "some samples start inside walls";
  EXPECT_LT(st.missed_both, 20u) << "a closed building: almost every sample sees something";
  // Samples inside the facades and outer slabs exit on the scene bounds: no segment there.
  EXPECT_GT(st.outside_view_box, 0u);
  EXPECT_GT(st.valid_segments, 15000u);
  const Violations v = check_segments(scene, r.segments, 1500, 1e-5 * scene.bounds.diagonal(), true);
  EXPECT_GT(v.checked, 1000);
  EXPECT_EQ(v.outside_box, 0);
  EXPECT_EQ(v.wrong_object, 0) << v.examples;
  EXPECT_EQ(v.blocked, 0);
  EXPECT_EQ(v.inside_solid, 0) << v.examples;
  uint64_t per_object = 0;
  for (uint64_t n : st.segments_per_object) per_object += n;
  EXPECT_GE(per_object, st.valid_segments);
}

TEST(Sampler, WithoutEmptySpaceDetectionSegmentsRunInsideSolids) {
  // The same check must be able to fail: switched off, segments start inside walls.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const SamplingResult r = sample(scene, 5000, 1, EmptySpaceMode::kOff);
  EXPECT_FALSE(r.stats.empty_space.enabled);
  EXPECT_EQ(r.stats.recast_rays, 0u);
  const Violations v = check_segments(scene, r.segments, 1000, 1e-5 * scene.bounds.diagonal(), true);
  EXPECT_GT(v.inside_solid, 10);
}

TEST(Sampler, EmptySpaceDetectionOnlyForSolidScenes) {
  RawMesh mesh;
  test::add_cube(mesh, {0, 0, 0}, {1, 1, 1}, "closed");
  test::add_cube(mesh, {2, 0, 0}, {3, 1, 1}, "open");
  mesh.triangles.pop_back();
  mesh.triangle_group.pop_back();
  const Scene open = make_scene(mesh, ObjectGrouping::kGroups, "t");
  const EmptySpaceDecision d = decide_empty_space(open, EmptySpaceMode::kAuto);
  EXPECT_FALSE(d.enabled);
  EXPECT_NE(d.reason.find("'open' is open"), std::string::npos) << d.reason;
  EXPECT_TRUE(decide_empty_space(open, EmptySpaceMode::kOn).enabled);
  EXPECT_FALSE(decide_empty_space(test::cube_grid(2), EmptySpaceMode::kOff).enabled);
  EXPECT_TRUE(decide_empty_space(test::cube_grid(2), EmptySpaceMode::kAuto).enabled);
  EXPECT_THROW(parse_empty_space_mode("maybe"), Error);
}

TEST(Sampler, IdenticalForOneAndTwoThreads) {
  const Scene scene = generate_scene({GeneratorKind::kCity, 2, 3});
  SamplingResult one, two;
  {
    ThreadLimit limit(1);
    one = sample(scene, 30000, 9);
  }
  {
    ThreadLimit limit(2);
    two = sample(scene, 30000, 9);
  }
  EXPECT_GT(one.segments.size(), 10000u);
  EXPECT_TRUE(one.segments == two.segments) << "output must not depend on the thread count";
  EXPECT_EQ(one.stats.rays, two.stats.rays);
  EXPECT_FALSE(sample(scene, 30000, 10).segments == one.segments) << "the seed matters";
}

TEST(Sampler, UserViewBoxClipsButKeepsObjectsBeyond) {
  const Scene scene = generate_scene({GeneratorKind::kCity, 4, 2});
  // A street-level band over part of the city.
  const Box3 box{{20, 20, 0.5}, {120, 120, 10}};
  const SamplingResult r = sample(scene, 20000, 2, EmptySpaceMode::kAuto, box);
  EXPECT_FALSE(r.stats.view_box_from_scene);
  size_t clipped_with_object = 0;
  for (size_t i = 0; i < r.segments.size(); ++i) {
    ASSERT_TRUE(box.contains(r.segments.a(i)) && box.contains(r.segments.b(i)));
    // An end on the box boundary that still names an object: that object lies beyond the box.
    for (int end = 0; end < 2; ++end) {
      const Vec3 p = end ? r.segments.b(i) : r.segments.a(i);
      const uint32_t o = end ? r.segments.object_b[i] : r.segments.object_a[i];
      const bool on_boundary = p.x == box.lo.x || p.x == box.hi.x || p.y == box.lo.y || p.y == box.hi.y ||
                               p.z == box.hi.z;
      clipped_with_object += on_boundary && o != kNoObject;
    }
  }
  EXPECT_GT(clipped_with_object, 100u);
  const Violations v = check_segments(scene, r.segments, 800, 1e-5 * scene.bounds.diagonal(), false);
  EXPECT_EQ(v.blocked, 0);
}

TEST(Sampler, HardCasesKeepInvariants) {
  // Rotated walls (every ray meets them obliquely) and coordinates around 1e5.
  Scene rotated = generate_scene({GeneratorKind::kRotatedOffice, 4, 2});
  Scene far = generate_scene({GeneratorKind::kOffice, 4, 2});
  translate(far, {1e5, -1e5, 1e5});
  for (const Scene* scene : {&rotated, &far}) {
    const SamplingResult r = sample(*scene, 10000, 5);
    EXPECT_TRUE(r.stats.empty_space.enabled);
    EXPECT_EQ(r.stats.stuck_in_solid, 0u);
    const Violations v = check_segments(*scene, r.segments, 800, 1e-5 * scene->bounds.diagonal(), true);
    EXPECT_EQ(v.outside_box, 0) << scene->source;
    EXPECT_EQ(v.wrong_object, 0) << scene->source;
    EXPECT_EQ(v.blocked, 0) << scene->source;
    EXPECT_EQ(v.inside_solid, 0) << scene->source << "\n" << v.examples;
  }
}

TEST(Sampler, SampledRaysAreTheSamplersRays) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 1});
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = 2500;
  config.batch_size = 1000;
  config.show_progress = false;
  const SamplingResult r = sample_segments(scene, *caster, config);
  const std::vector<Ray> rays = sampled_rays(scene, *caster, config);
  ASSERT_EQ(rays.size(), r.stats.rays) << "primary pairs plus re-casts";
  // Each batch starts with its samples' forward/backward pairs from points inside the box.
  for (size_t i = 0; i < 2000; i += 2) {
    EXPECT_EQ(rays[i].origin, rays[i + 1].origin);
    EXPECT_EQ(rays[i].dir, -rays[i + 1].dir);
    EXPECT_NEAR(length(rays[i].dir), 1.0, 1e-12);
    EXPECT_TRUE(scene.bounds.contains(rays[i].origin));
  }
  // Re-casts start past an exit surface (tnear > 0).
  size_t recasts = 0;
  for (const Ray& ray : rays) recasts += ray.tnear > 0;
  EXPECT_EQ(recasts, r.stats.recast_rays);
}

TEST(Sampler, ViewSpaceRejectsOriginsOutsideIt) {
  // A view space that is half the box: every origin lies in it, about half the draws are
  // rejected, and the output still does not depend on the thread count.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 1});
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = 20000;
  config.empty_space = EmptySpaceMode::kOff;  // no re-casts: the rays come in origin pairs
  config.show_progress = false;
  const double mid = scene.bounds.center().x;
  config.view_space = [mid](const Vec3& p) { return p.x < mid; };
  SamplingResult one;
  {
    ThreadLimit limit(1);
    one = sample_segments(scene, *caster, config);
  }
  const SamplingResult two = sample_segments(scene, *caster, config);
  EXPECT_TRUE(one.segments == two.segments);
  EXPECT_EQ(one.stats.samples, 20000u);
  EXPECT_NEAR(static_cast<double>(one.stats.rejected_origins), 20000.0, 1500.0);
  const std::vector<Ray> rays = sampled_rays(scene, *caster, config);
  ASSERT_EQ(rays.size(), 40000u);
  for (size_t i = 0; i < rays.size(); i += 2) ASSERT_LT(rays[i].origin.x, mid);
  // An empty view space is an error, not an endless loop.
  config.view_space = [](const Vec3&) { return false; };
  EXPECT_THROW(sample_segments(scene, *caster, config), Error);
}

TEST(Sampler, SeeThroughObjectsAreSeenButStopNoRay) {
  // Two walls facing each other (x = 0 and x = 10) and a pane of glass between them at x = 5,
  // y and z in [2, 8], that occludes nothing.
  RawMesh mesh;
  auto quad = [&](double x, double lo, double hi, uint32_t group, bool facing_plus_x) {
    const uint32_t b = static_cast<uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {{x, lo, lo}, {x, hi, lo}, {x, hi, hi}, {x, lo, hi}});
    for (auto t : {std::array<uint32_t, 3>{b, b + 1, b + 2}, std::array<uint32_t, 3>{b, b + 2, b + 3}}) {
      if (!facing_plus_x) std::swap(t[1], t[2]);
      mesh.triangles.push_back(t);
      mesh.triangle_group.push_back(group);
    }
  };
  quad(0, 0, 10, 0, true);
  quad(10, 0, 10, 1, false);
  quad(5, 2, 8, 2, true);
  mesh.group_names = {"left", "right", "glass"};
  mesh.group_occluder = {1, 1, 0};
  const Scene scene = make_scene(mesh, ObjectGrouping::kGroups, "glass");
  ASSERT_FALSE(scene.objects[2].occluder);
  const auto caster = make_embree_caster(scene);
  EXPECT_FALSE(caster->intersect(Ray{{2, 5, 5}, {1, 0, 0}}).object == 2) << "the glass stops no ray";
  SamplerConfig config;
  config.samples = 20000;
  config.show_progress = false;
  SamplingResult r;
  {
    ThreadLimit limit(1);
    r = sample_segments(scene, *caster, config);
  }
  EXPECT_TRUE(sample_segments(scene, *caster, config).segments == r.segments) << "thread count";
  EXPECT_EQ(r.stats.see_through_objects, 1u);
  const SegmentSet& s = r.segments;
  std::set<std::array<double, 6>> with_glass;
  for (size_t i = 0; i < s.size(); ++i)
    if (s.object_a[i] == 2 || s.object_b[i] == 2) {
      ASSERT_TRUE(s.object_a[i] == 2 && s.object_b[i] == 2) << "a see-through object ends no ray";
      with_glass.insert({s.ax[i], s.ay[i], s.az[i], s.bx[i], s.by[i], s.bz[i]});
    }
  EXPECT_EQ(with_glass.size(), r.stats.see_through_segments);
  size_t crossing = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s.object_a[i] == 2) continue;
    const Vec3 a = s.a(i), b = s.b(i);
    if ((a.x - 5) * (b.x - 5) >= 0) continue;  // does not cross x = 5
    const Vec3 p = a + (b - a) * ((5 - a.x) / (b.x - a.x));
    const bool inside = p.y > 2.01 && p.y < 7.99 && p.z > 2.01 && p.z < 7.99;
    const bool outside = p.y < 1.99 || p.y > 8.01 || p.z < 1.99 || p.z > 8.01;
    const bool companion = with_glass.count({a.x, a.y, a.z, b.x, b.y, b.z}) > 0;
    if (inside) {
      EXPECT_TRUE(companion) << "crosses the glass at " << p.y << " " << p.z;
    }
    if (outside) {
      EXPECT_FALSE(companion);
    }
    crossing += inside;
  }
  EXPECT_GT(crossing, 500u);
  EXPECT_EQ(r.stats.valid_segments - r.stats.see_through_segments + r.stats.missed_both + r.stats.stuck_in_solid +
                r.stats.outside_view_box,
            r.stats.samples + r.stats.two_sided_samples);
}

/// A see-through surface on a wall (water against a wall, a decal): segments end on the wall
/// within a hair of the crossing, and the search for further crossings must stop at the
/// segment's end instead of asking the caster for an empty interval (found on a real map).
TEST(Sampler, SeeThroughSurfaceOnAWallEndsTheCrossingSearch) {
  RawMesh mesh;
  auto quad = [&](double x, uint32_t group, bool facing_plus_x) {
    const uint32_t b = static_cast<uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {{x, 0, 0}, {x, 10, 0}, {x, 10, 10}, {x, 0, 10}});
    for (auto t : {std::array<uint32_t, 3>{b, b + 1, b + 2}, std::array<uint32_t, 3>{b, b + 2, b + 3}}) {
      if (!facing_plus_x) std::swap(t[1], t[2]);
      mesh.triangles.push_back(t);
      mesh.triangle_group.push_back(group);
    }
  };
  quad(0, 0, true);
  quad(10, 1, false);
  for (double gap : {0.0, 1e-9, 1e-7, 5e-7}) quad(10 - gap, 2, false);  // the decal, on and just off the wall
  mesh.group_names = {"left", "right", "decal"};
  mesh.group_occluder = {1, 1, 0};
  const Scene scene = make_scene(mesh, ObjectGrouping::kGroups, "decal");
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = 20000;
  config.show_progress = false;
  const SamplingResult r = sample_segments(scene, *caster, config);
  EXPECT_GT(r.stats.see_through_segments, 1000u) << "the decal is seen";
  for (size_t i = 0; i < r.segments.size(); ++i) ASSERT_TRUE(std::isfinite(r.segments.bx[i]));
}

TEST(Sampler, DirectionsAreUniformOnTheSphere) {
  const Scene scene = test::cube_grid(2);
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = 200000;
  config.empty_space = EmptySpaceMode::kOff;
  const std::vector<Ray> rays = sampled_rays(scene, *caster, config);
  double mean[3] = {0, 0, 0}, second[3] = {0, 0, 0};
  int octant[8] = {0};
  for (size_t i = 0; i < rays.size(); i += 2) {
    const Vec3& d = rays[i].dir;
    ASSERT_NEAR(length(d), 1.0, 1e-12);
    for (int a = 0; a < 3; ++a) {
      mean[a] += d[a];
      second[a] += d[a] * d[a];
    }
    ++octant[(d.x > 0) | ((d.y > 0) << 1) | ((d.z > 0) << 2)];
  }
  const double n = config.samples;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(mean[a] / n, 0.0, 0.01) << "axis " << a;
    EXPECT_NEAR(second[a] / n, 1.0 / 3.0, 0.01) << "axis " << a;  // E[d_a^2] = 1/3 when uniform
  }
  for (int o : octant) EXPECT_NEAR(o / n, 0.125, 0.005);
}

TEST(Sampler, SegmentTargetIsAPrefixOfTheSampleStream) {
  const Scene scene = generate_scene({GeneratorKind::kCity, 6, 2});
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.show_progress = false;
  config.samples = 60000;
  const SamplingResult all = sample_segments(scene, *caster, config);
  config.target_segments = 25000;
  SamplingResult target;
  {
    ThreadLimit one(1);
    target = sample_segments(scene, *caster, config);
  }
  ASSERT_EQ(target.segments.size(), 25000u);
  ASSERT_GT(all.segments.size(), 25000u);
  EXPECT_EQ(target.stats.valid_segments, 25000u);
  EXPECT_LT(target.stats.samples, 60000u);
  EXPECT_EQ(target.stats.samples % config.batch_size, 0u) << "whole batches";
  for (size_t i = 0; i < 25000; i += 97) {
    ASSERT_EQ(target.segments.a(i), all.segments.a(i)) << i;
    ASSERT_EQ(target.segments.object_b[i], all.segments.object_b[i]) << i;
  }
  // An unreachable target gives up with an error rather than looping.
  config.view_box = Box3{{-1e6, -1e6, 500}, {-1e6 + 50, -1e6 + 50, 600}};  // sky far from the city
  config.target_segments = 10;
  config.max_samples = 20000;
  EXPECT_THROW(sample_segments(scene, *caster, config), Error);
  // Without a sample cap it gives up after a million samples that saw nothing.
  config.max_samples = SamplerConfig{}.max_samples;
  try {
    sample_segments(scene, *caster, config);
    ADD_FAILURE() << "an unreachable target must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gave up after 1000448 samples"), std::string::npos) << e.what();
  }
}

/// Chunks of one stream, each drawn with its own first batch, are the whole stream: the
/// evaluator draws millions of samples that way without holding them all.
TEST(Sampler, ChunksOfAStreamAreTheStream) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.show_progress = false;
  config.samples = 20000;  // not a multiple of the batch size: the last chunk's batch is short
  config.seed = 4;
  const SamplingResult all = sample_segments(scene, *caster, config);
  SegmentSet joined;
  joined.view_box = all.segments.view_box;
  size_t chunks = 0;
  const SamplingStats stats =
      sample_in_chunks(scene, *caster, config, 3000, [&](const SegmentSet& chunk, uint64_t so_far) {
        EXPECT_EQ(chunk.view_box, joined.view_box);
        joined.append(chunk);
        ++chunks;
        EXPECT_EQ(so_far, std::min<uint64_t>(20000, chunks * 2048));
      });
  EXPECT_EQ(chunks, 10u) << "3000 rounds down to two batches of 1024: 20000 samples in ten chunks";
  EXPECT_TRUE(joined == all.segments) << joined.size() << " segments against " << all.segments.size();
  EXPECT_EQ(stats.samples, all.stats.samples);
  EXPECT_EQ(stats.rays, all.stats.rays);
  EXPECT_EQ(stats.valid_segments, all.stats.valid_segments);
  EXPECT_EQ(stats.segments_per_object, all.stats.segments_per_object);
  config.target_segments = 100;
  EXPECT_THROW(sample_in_chunks(scene, *caster, config, 3000, [](const SegmentSet&, uint64_t) {}), Error);
}

TEST(Sampler, BadInput) {
  const Scene scene = test::cube_grid(2);
  EXPECT_THROW(sample(scene, 10, 1, EmptySpaceMode::kAuto, Box3{{0, 0, 0}, {1, 1, 0}}), Error);
  Scene flat = scene;
  for (Vec3& v : flat.vertices) v.z = 0;
  flat.finalize();
  EXPECT_THROW(sample(flat, 10, 1), Error) << "a flat scene has no view volume unless a box is given";
}

}  // namespace
}  // namespace viewcells
