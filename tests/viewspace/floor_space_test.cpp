// The play space found from a scene's floors (viewspace/floor_space.h): a small level with two
// storeys joined by stairs, a pedestal, a walled-off room and a roof, in metres and in Quake
// units; what a player can reach is in, the rest is not.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "support/test_scenes.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/scene.h"
#include "viewcells/vis/level_view.h"
#include "viewcells/viewspace/floor_space.h"

namespace viewcells {
namespace {

using test::add_cube;
using test::temp_path;

/// A quad a-b-c-d (counter-clockwise seen from where its normal points) as two triangles.
void add_quad(RawMesh& m, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const std::string& group) {
  uint32_t g = 0;
  while (g < m.group_names.size() && m.group_names[g] != group) ++g;
  if (g == m.group_names.size()) m.group_names.push_back(group);
  const uint32_t v = static_cast<uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c, d});
  m.triangles.push_back({v, v + 1, v + 2});
  m.triangles.push_back({v, v + 2, v + 3});
  m.triangle_group.insert(m.triangle_group.end(), {g, g});
}

/// An up-facing rectangle at height z.
void add_floor(RawMesh& m, double x0, double y0, double x1, double y1, double z, const std::string& group) {
  add_quad(m, {x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, group);
}

/// The level, in metres times `k`: a ground floor 20 x 10; an upper storey over x in [10, 20]
/// at 3 m (a slab 0.1 thick: its underside is the ceiling below); stairs of 0.25 m steps up
/// to it along y in [0, 2]; a pedestal 1 x 1 x 2 m; a room x in [0, 3], y in [7, 10] walled off
/// (walls 6 m tall); a roof slab at 6 m over everything.
RawMesh level(double k, bool stairs = true) {
  RawMesh m;
  add_floor(m, 0, 0, 20, 10, 0, "ground");
  add_cube(m, {10, 2.05, 2.9}, {20, 10, 3.0}, "upper");
  if (stairs)
    for (int s = 0; s < 12; ++s) {
      const double x = 6.4 + 0.3 * s, z = 0.25 * (s + 1);
      add_cube(m, {x, 0, 0}, {x + 0.3, 2, z}, "stairs");
    }
  add_cube(m, {10, 0, 2.9}, {20, 0.05, 3.0}, "landing edge");  // nothing: a thin lip
  add_floor(m, 10, 0.05, 20, 2.05, 3.0, "landing");
  add_cube(m, {4, 4, 0}, {5, 5, 2}, "pedestal");
  add_cube(m, {0, 6.9, 0}, {3.1, 7, 6}, "wall a");
  add_cube(m, {3, 7, 0}, {3.1, 10, 6}, "wall b");
  add_cube(m, {0, 0, 6}, {20, 10, 6.2}, "roof");
  for (Vec3& v : m.vertices) v = v * k;
  return m;
}

struct Level {
  explicit Level(double k, bool stairs = true, std::vector<Vec3> starts = {{15 * 1.0, 4, 0.5}}, bool only = true)
      : scene(make_scene(level(k, stairs), ObjectGrouping::kGroups, "level")),
        caster(make_embree_caster(scene, {})) {
    config.metres_per_unit = 1 / k;
    for (Vec3& p : starts) p = p * k;
    config.start_points = starts;
    config.only_from_starts = only;
    space = find_floor_space(scene, *caster, config);
  }
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  FloorSpaceConfig config;
  FloorSpace space = FloorSpace();
};

TEST(FloorSpace, WhatAPlayerReachesIsInTheRestIsNot) {
  const Level l(1);
  ASSERT_FALSE(l.space.empty()) << l.space.rule();
  EXPECT_NE(l.space.rule().find("reachable from 1 of 1 start points"), std::string::npos) << l.space.rule();
  const FloorSpace& s = l.space;
  EXPECT_TRUE(s.contains({7, 5, 1.6})) << s.rule();  // ground floor
  EXPECT_TRUE(s.contains({12, 5, 1.6}));          // under the upper storey (2.9 m free)
  EXPECT_TRUE(s.contains({15, 5, 3.0 + 1.6}));    // upper storey, by the stairs
  EXPECT_TRUE(s.contains({8, 1, 1.5 + 1.6}));     // on the stairs
  EXPECT_FALSE(s.contains({7, 5, 0.5}));          // below the eye band
  EXPECT_FALSE(s.contains({7, 5, 3.5}));          // above it
  EXPECT_FALSE(s.contains({1.5, 8.5, 1.6}));      // the walled-off room
  EXPECT_FALSE(s.contains({4.5, 4.5, 2 + 1.6})); // on the pedestal: 2 m up, no step that high
  EXPECT_FALSE(s.contains({7, 5, 6.2 + 1.6}));    // on the roof
  EXPECT_FALSE(s.contains({7, 5, -1.6}));         // under the level
  // The floor area: the ground (200 m^2 less the room 9.3, the pedestal, the walls and the
  // stairs' foot) and the upper storey (100), within a column's width of each edge.
  const double area = s.floor_area();
  EXPECT_GT(area, 270);
  EXPECT_LT(area, 300);
}

TEST(FloorSpace, WithoutTheStairsTheUpperStoreyIsOutOfReach) {
  const Level l(1, false);
  EXPECT_TRUE(l.space.contains({7, 5, 1.6}));
  EXPECT_FALSE(l.space.contains({15, 5, 3.0 + 1.6}));
}

TEST(FloorSpace, WithoutStartPointsEveryLargeRegionIsAStart) {
  const Level l(1, true, {});
  EXPECT_NE(l.space.rule().find("no start points"), std::string::npos) << l.space.rule();
  EXPECT_TRUE(l.space.contains({1.5, 8.5, 1.6}));   // the walled-off room is a region of its own
  EXPECT_FALSE(l.space.contains({7, 5, 6.2 + 1.6}));  // the roof too, but eyes above the scene's top are never in
  EXPECT_FALSE(l.space.contains({4.5, 4.5, 2 + 1.6}));  // the pedestal's 1 m^2 is not
}

TEST(FloorSpace, ByDefaultLargeRegionsJoinWhatTheStartsReach) {
  // What walking from the start misses (the walled-off room) is in by default, as a region of
  // its own; the pedestal's 1 m^2 is not; the rule says both.
  const Level l(1, true, {{15, 4, 0.5}}, false);
  EXPECT_TRUE(l.space.contains({1.5, 8.5, 1.6}));
  EXPECT_TRUE(l.space.contains({15, 5, 4.6}));
  EXPECT_FALSE(l.space.contains({4.5, 4.5, 2 + 1.6}));
  EXPECT_NE(l.space.rule().find("reachable from 1 of 1 start points and from every floor region"), std::string::npos)
      << l.space.rule();
}

TEST(FloorSpace, ABackdropFarFromWhatTheStartsReachStaysOut) {
  // A landscape 30 m beyond the level (a map's backdrop): a region of its own, far from what
  // the start reaches: out by default, in without start points or with a wider margin.
  RawMesh m = level(1);
  add_floor(m, 50, 0, 70, 20, 0, "backdrop");
  const Scene scene = make_scene(m, ObjectGrouping::kGroups, "level and backdrop");
  const auto caster = make_brute_force_caster(scene);
  FloorSpaceConfig c;
  c.start_points = {{15, 4, 0.5}};
  const Vec3 backdrop{60, 10, 1.6}, room{1.5, 8.5, 1.6};
  const FloorSpace near = find_floor_space(scene, *caster, c);
  EXPECT_TRUE(near.contains(room)) << near.rule();
  EXPECT_FALSE(near.contains(backdrop)) << near.rule();
  c.region_margin = 40;
  EXPECT_TRUE(find_floor_space(scene, *caster, c).contains(backdrop));
  c.start_points.clear();
  c.region_margin = 10;
  EXPECT_TRUE(find_floor_space(scene, *caster, c).contains(backdrop));
}

TEST(FloorSpace, ASkyIsNoFloor) {
  // A sky below the level (a death pit): its surface faces up, but a sky is never a floor.
  RawMesh m = level(1);
  add_floor(m, -20, -20, 40, 30, -10, "textures/skies/pit");
  const Scene scene = make_scene(m, ObjectGrouping::kGroups, "level over a sky");
  const auto caster = make_brute_force_caster(scene);
  FloorSpaceConfig c;
  c.start_points = {{15, 4, 0.5}};
  const FloorSpace s = find_floor_space(scene, *caster, c);
  EXPECT_TRUE(s.contains({7, 5, 1.6}));
  EXPECT_FALSE(s.contains({30, 25, -10 + 1.6}));  // drops from the level's edge land on the sky
  EXPECT_TRUE(sky_name("textures/skies/pit") && sky_name("SkyBox") && !sky_name("floor"));
}

TEST(FloorSpace, QuakeUnitsGiveTheSameSpaceAsMetres) {
  const Level m(1), q(32);
  ASSERT_FALSE(q.space.empty()) << q.space.rule();
  const double k3 = 32.0 * 32 * 32;
  EXPECT_NEAR(q.space.volume() / k3, m.space.volume(), 0.02 * m.space.volume());
  for (const Vec3& p : std::vector<Vec3>{{7, 5, 1.6}, {15, 5, 4.6}, {1.5, 8.5, 1.6}, {7, 5, 7.8}, {8, 1, 3.1}})
    EXPECT_EQ(q.space.contains(p * 32), m.space.contains(p)) << p.x << ' ' << p.y << ' ' << p.z;
}

TEST(FloorSpace, PointsAreInsideAndThreadsChangeNothing) {
  const Level l(1);
  const std::vector<Vec3> points = l.space.uniform_points(2000, 7);
  for (const Vec3& p : points) ASSERT_TRUE(l.space.contains(p)) << p.x << ' ' << p.y << ' ' << p.z;
  // The upper storey holds about a third of the eye band: its share of the points agrees.
  size_t upper = 0;
  for (const Vec3& p : points) upper += p.z > 3.5;
  const double share = upper / 2000.0, expected = 100.0 / l.space.floor_area();
  EXPECT_NEAR(share, expected, 4 * std::sqrt(expected * (1 - expected) / 2000) + 0.03);
  FloorSpace one = FloorSpace();
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = find_floor_space(l.scene, *l.caster, l.config);
  }
  EXPECT_EQ(one.volume(), l.space.volume());
  EXPECT_EQ(one.reached_spans(), l.space.reached_spans());
  EXPECT_EQ(one.uniform_points(2000, 7).size(), points.size());
}

TEST(FloorSpace, ASceneWithoutFloorsHasNone) {
  RawMesh m;
  add_quad(m, {0, 0, 0}, {0, 10, 0}, {0, 10, 5}, {0, 0, 5}, "wall");   // walls only
  add_quad(m, {0, 0, 0}, {0, 0, 5}, {10, 0, 5}, {10, 0, 0}, "wall 2");
  add_floor(m, 0, 0, 10, 10, 0, "floor under a low ceiling");
  add_quad(m, {0, 0, 1}, {0, 10, 1}, {10, 10, 1}, {10, 0, 1}, "ceiling");  // faces down, 1 m up
  const Scene scene = make_scene(m, ObjectGrouping::kGroups, "no floor");
  const auto caster = make_embree_caster(scene, {});
  const FloorSpace s = find_floor_space(scene, *caster, {});
  EXPECT_TRUE(s.empty());
  EXPECT_NE(s.rule().find("no walkable floor"), std::string::npos) << s.rule();
  EXPECT_FALSE(mesh_view_space()->play_space(scene, *caster));
}

TEST(FloorSpace, BadBodiesAreErrors) {
  const Level l(1);
  for (auto bad : {+[](FloorSpaceConfig& c) { c.cell = 0; }, +[](FloorSpaceConfig& c) { c.eye_high = c.eye_low; },
                   +[](FloorSpaceConfig& c) { c.walk_normal = 1.5; }, +[](FloorSpaceConfig& c) { c.step = -1; },
                   +[](FloorSpaceConfig& c) { c.metres_per_unit = std::nan(""); }}) {
    FloorSpaceConfig c = l.config;
    bad(c);
    EXPECT_THROW(find_floor_space(l.scene, *l.caster, c), Error);
  }
}

TEST(FloorSpace, AGltfLevelKeepsItsStartPointsAndUnits) {
  // Written in metres from Quake units (1/32 m), read back: y-up turned to z-up, metres, the
  // spawn nodes as start points.
  const Level q(32);
  SceneGltfOptions o;
  o.metres_per_unit = 1.0 / 32;
  o.start_points = {Vec3{15, 4, 0.5} * 32};
  const std::string path = temp_path("floor_level.glb");
  write_scene_gltf(path, q.scene, o);
  const Scene back = load_scene(path, ObjectGrouping::kAuto);
  EXPECT_EQ(back.metres_per_unit, 1);
  ASSERT_EQ(back.start_points.size(), 1u);
  EXPECT_NEAR(back.start_points[0].x, 15, 1e-4);
  EXPECT_NEAR(back.start_points[0].y, 4, 1e-4);
  EXPECT_NEAR(back.start_points[0].z, 0.5, 1e-4);
  EXPECT_NEAR(back.bounds.hi.z, 6.2, 1e-4);
  const auto caster = make_embree_caster(back, {});
  FloorSpaceConfig only;
  only.only_from_starts = true;  // the file's start point alone: the walled-off room is out
  const FloorSpace s = find_floor_space(back, *caster, only);
  EXPECT_NE(s.rule().find("from the file"), std::string::npos) << s.rule();
  EXPECT_NE(s.rule().find("reachable from 1 of 1 start points"), std::string::npos) << s.rule();
  EXPECT_TRUE(s.contains({15, 5, 4.6}));
  EXPECT_FALSE(s.contains({1.5, 8.5, 1.6}));
}

}  // namespace
}  // namespace viewcells
