// Near-object samples (pvs/near_samples.h): neighbours by box distance, and what a cell's rays
// add: visible neighbours of its PVS, never hidden ones, never objects that touch nothing it sees.
#include <gtest/gtest.h>

#include <algorithm>

#include "support/test_scenes.h"
#include "viewcells/core/parallel.h"
#include "viewcells/pvs/near_samples.h"
#include "viewcells/raycast/ray_caster.h"

namespace viewcells {
namespace {

/// A wall at x in [0, 0.2] seen from eyes at x = -2; a trim on its near side and a glass pane
/// against it (both neighbours, both visible), a box on its far side (a neighbour, hidden), and
/// a box in the open that touches nothing (visible, not a neighbour).
struct WallScene {
  Scene scene;
  uint32_t wall = 0, trim = 0, glass = 0, hidden = 0, far = 0;
  WallScene() {
    RawMesh mesh;
    test::add_cube(mesh, {0, -5, 0}, {0.2, 5, 3}, "wall");
    test::add_cube(mesh, {-0.1, 0, 0}, {0, 0.5, 0.1}, "trim");
    test::add_cube(mesh, {-0.05, -3, 1}, {0, -2, 2}, "glass");
    test::add_cube(mesh, {0.2, 0, 0}, {0.3, 0.5, 0.1}, "hidden");
    test::add_cube(mesh, {-3, 3, 0}, {-2.5, 3.5, 0.5}, "far");
    mesh.group_occluder = {1, 1, 0, 1, 1};
    scene = make_scene(std::move(mesh), ObjectGrouping::kGroups, "wall scene");
    auto id = [&](const std::string& name) {
      for (uint32_t o = 0; o < scene.object_count(); ++o)
        if (scene.objects[o].name == name) return o;
      ADD_FAILURE() << name;
      return 0u;
    };
    wall = id("wall"), trim = id("trim"), glass = id("glass"), hidden = id("hidden"), far = id("far");
  }
};

TEST(NearSamples, NeighboursAreBoxesWithinTheDistanceBothWays) {
  const WallScene w;
  const auto near = object_neighbours(w.scene, 0.01);
  std::vector<uint32_t> wall_near = {w.trim, w.glass, w.hidden};
  std::sort(wall_near.begin(), wall_near.end());
  EXPECT_EQ(near[w.wall], wall_near);
  EXPECT_EQ(near[w.trim], std::vector<uint32_t>{w.wall});
  EXPECT_TRUE(near[w.far].empty());
  for (uint32_t a = 0; a < near.size(); ++a)
    for (uint32_t b : near[a]) EXPECT_TRUE(std::binary_search(near[b].begin(), near[b].end(), a));
  // Wider, the trim and the hidden box (0.2 apart through the wall) become neighbours.
  const auto wide = object_neighbours(w.scene, 0.25);
  EXPECT_TRUE(std::binary_search(wide[w.trim].begin(), wide[w.trim].end(), w.hidden));
}

TEST(NearSamples, AddVisibleNeighboursOnlyAndDoNotDependOnTheThreads) {
  const WallScene w;
  const auto caster = make_embree_caster(w.scene);
  std::vector<Vec3> eyes;
  for (int i = 0; i < 32; ++i) eyes.push_back({-2.0, -1.0 + i / 16.0, 1.5});
  // Cell 0 sees the wall; cell 1 the far box alone; cell 2 the wall but has no viewpoints.
  std::vector<std::vector<uint32_t>> lists = {{w.wall}, {w.far}, {w.wall}};
  const std::vector<std::vector<Vec3>> cell_eyes = {eyes, eyes, {}};
  NearSampleConfig config;
  config.rays_per_object = 64;
  config.distance = 0.01;
  const NearSampleStats stats = add_near_samples(w.scene, *caster, cell_eyes, config, lists);
  std::vector<uint32_t> expected = {w.wall, w.trim, w.glass};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(lists[0], expected);  // the trim and the glass, seen; the hidden box, behind the wall, not
  EXPECT_EQ(lists[1], std::vector<uint32_t>{w.far});  // the far box touches nothing
  EXPECT_EQ(lists[2], std::vector<uint32_t>{w.wall});  // no viewpoints: left as it was
  EXPECT_EQ(stats.added, 2u);
  // Round 1 tests the wall's three neighbours; round 2 would test the neighbours of the trim and
  // the glass, the wall alone, which the PVS holds: there is no round 2.
  EXPECT_EQ(stats.tested, 3u);
  EXPECT_EQ(stats.added_by_round, (std::vector<uint64_t>{2}));
  EXPECT_EQ(stats.rays_by_round, (std::vector<uint64_t>{64}));
  EXPECT_EQ(stats.rays, stats.tested * config.rays_per_object);
  // Once more: nothing to add. And one thread gives the same lists.
  auto again = lists;
  EXPECT_EQ(add_near_samples(w.scene, *caster, cell_eyes, config, again).added, 0u);
  std::vector<std::vector<uint32_t>> serial = {{w.wall}, {w.far}, {w.wall}};
  ThreadLimit one(1);
  add_near_samples(w.scene, *caster, cell_eyes, config, serial);
  EXPECT_EQ(serial, lists);
}

TEST(NearSamples, TheRayBudgetLowersTheRaysACandidateInPackets) {
  const WallScene w;
  const auto caster = make_embree_caster(w.scene);
  const std::vector<std::vector<Vec3>> cell_eyes = {{{-2.0, 0.25, 1.5}}};
  NearSampleConfig config;
  config.rays_per_object = 1024;
  config.distance = 0.01;
  config.max_rays = 3 * 100;  // three candidates: 100 rays each, down to 96 in whole packets
  std::vector<std::vector<uint32_t>> lists = {{w.wall}};
  const NearSampleStats stats = add_near_samples(w.scene, *caster, cell_eyes, config, lists);
  EXPECT_EQ(stats.rays_by_round, (std::vector<uint64_t>{96}));
  EXPECT_EQ(stats.rays, 3u * 96u);
  // Too little for a packet a candidate: nothing is cast.
  config.max_rays = 3 * 15;
  std::vector<std::vector<uint32_t>> none = {{w.wall}};
  EXPECT_EQ(add_near_samples(w.scene, *caster, cell_eyes, config, none).rays, 0u);
  EXPECT_EQ(none, (std::vector<std::vector<uint32_t>>{{w.wall}}));
}

TEST(NearSamples, ATimeLimitStopsThem) {
  const WallScene w;
  const auto caster = make_embree_caster(w.scene);
  const std::vector<std::vector<Vec3>> cell_eyes = {{{-2.0, 0.25, 1.5}}};
  NearSampleConfig config;
  config.distance = 0.01;
  config.max_seconds = 1e-12;  // spent before the first cell
  std::vector<std::vector<uint32_t>> lists = {{w.wall}};
  const NearSampleStats stats = add_near_samples(w.scene, *caster, cell_eyes, config, lists);
  EXPECT_TRUE(stats.stopped_by_time);
  EXPECT_EQ(stats.added, 0u);
  EXPECT_EQ(lists, (std::vector<std::vector<uint32_t>>{{w.wall}}));
}

}  // namespace
}  // namespace viewcells
