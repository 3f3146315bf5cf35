// The map's BSP as a Subdivision, its view space and clusters: on a hand-built map with an
// axial plane whose normal points down its axis and an oblique plane (exact volumes known),
// and on OpenArena's oa_dm2 when scripts/fetch-maps.sh has fetched it (CI does; set
// VIEWCELLS_REQUIRE_MAPS=1 to make its absence a failure rather than a skip).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/core/rng.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/studies/q3map2.h"
#include "viewcells/q3/view_space.h"
#include "viewcells/raycast/ray_caster.h"

namespace viewcells {
namespace {

/// x > 0 is solid (node 0's plane has normal -x: its front is x <= 0); the rest is split by
/// the oblique plane 0.6 x + 0.8 y = 0 into cluster 0 (front) and cluster 1 (back).
/// Surface 0 lies in leaf 1 (cluster 0), surface 1 in leaf 2 (cluster 1); cluster 1 sees
/// both clusters, cluster 0 only itself.
Q3Map small_map() {
  Q3Map m;
  m.path = "small.bsp";
  m.planes = {{{-1, 0, 0}, 0}, {{0.6, 0.8, 0}, 0}};
  m.nodes = {{0, {1, -1}}, {1, {-2, -3}}};
  const Box3 solid{{0, -10, -10}, {10, 10, 10}}, open{{-10, -10, -10}, {0, 10, 10}};
  m.leaves = {{-1, 0, solid, 0, 0}, {0, 0, open, 0, 1}, {1, 0, open, 1, 1}};
  m.leaf_surfaces = {0, 1};
  m.shaders = {{"textures/wall", 0, 1}};
  m.surfaces.resize(2);
  m.cluster_count = 2;
  m.cluster_bytes = 1;
  m.visibility = {0x1, 0x3};
  return m;
}

const Box3 kBox{{-10, -10, -10}, {10, 10, 10}};

TEST(Q3ViewSpace, SubdivisionLocatesLikeTheMap) {
  const Q3Map map = small_map();
  const Subdivision s = q3_subdivision(map, kBox);
  Rng rng(7, 0);
  for (int i = 0; i < 10000; ++i) {
    const Vec3 p{-10 + 20 * rng.uniform(), -10 + 20 * rng.uniform(), -10 + 20 * rng.uniform()};
    const int32_t node = s.locate(p);
    ASSERT_GE(node, 0);
    EXPECT_EQ(q3_leaf_of_node(map, node), map.leaf_at(p)) << p.x << " " << p.y << " " << p.z;
    EXPECT_EQ(q3_in_view_space(map, p), p.x <= 0);
  }
}

/// Columns of points `base + (0, 0, h)` for ascending h, some repeated, some on a plane.
void expect_columns_find_the_leaves_of_their_points(const Q3Map& map, const Box3& box, int columns) {
  Rng rng(11, 0);
  const Vec3 e = box.extent();
  std::vector<double> heights;
  std::vector<int32_t> leaves;
  for (int i = 0; i < columns; ++i) {
    const Vec3 base{box.lo.x + e.x * rng.uniform(), box.lo.y + e.y * rng.uniform(), 0};
    heights.clear();
    double h = box.lo.z + e.z * 0.2 * rng.uniform();
    for (uint32_t k = 0, n = rng.below(100); k < n; ++k) {  // over 64 at times
      heights.push_back(h);
      if (rng.below(8)) h += e.z * 0.02 * rng.uniform();
    }
    // A point exactly on a horizontal plane, where the side test decides by its sign alone.
    const Q3Plane& pl = map.planes[rng.below(static_cast<uint32_t>(map.planes.size()))];
    if (pl.normal.x == 0 && pl.normal.y == 0 && std::abs(pl.normal.z) == 1) {
      heights.push_back(pl.dist * pl.normal.z);
      std::sort(heights.begin(), heights.end());
    }
    map.column_leaves(base, heights, leaves);
    ASSERT_EQ(leaves.size(), heights.size());
    for (size_t k = 0; k < heights.size(); ++k)
      ASSERT_EQ(leaves[k], map.leaf_at(base + Vec3{0, 0, 1} * heights[k]))
          << "column " << i << " at (" << base.x << ", " << base.y << "), height " << heights[k];
  }
}

TEST(Q3ViewSpace, ColumnsFindTheLeavesOfTheirPoints) {
  Q3Map map = small_map();
  expect_columns_find_the_leaves_of_their_points(map, kBox, 5000);
  // A sloped plane splits a column in the middle, and a horizontal one at a point on it.
  map.planes = {{{0, 0, 1}, 2.5}, {{0.6, 0, 0.8}, 1}};
  expect_columns_find_the_leaves_of_their_points(map, kBox, 5000);
  std::vector<int32_t> leaves;
  map.column_leaves({0, 0, 0}, std::vector<double>{-5, 2.5, 2.5, 7}, leaves);
  EXPECT_EQ(leaves, (std::vector<int32_t>{0, 1, 1, 1}));  // on the plane is in front
  map.column_leaves({0, 0, 0}, std::vector<double>{}, leaves);
  EXPECT_TRUE(leaves.empty());
  EXPECT_THROW(map.column_leaves({0, 0, 0}, std::vector<double>{1, 0}, leaves), Error);
  // A node tree with a cycle is an error, as for a single point.
  map.nodes = {{0, {1, -1}}, {1, {0, -3}}};
  EXPECT_THROW(map.column_leaves({0, 0, 0}, std::vector<double>{-5, 5}, leaves), Error);
  EXPECT_THROW(map.leaf_at({0, 0, 5}), Error);
}

TEST(Q3ViewSpace, LeafVolumesAndWeightsAreExact) {
  const Q3Map map = small_map();
  const Subdivision s = q3_subdivision(map, kBox);
  const int32_t leaf0 = static_cast<int32_t>(map.nodes.size());
  // Above the oblique plane within x in [-10, 0]: (100 - 0.75 * 50) * 20 = 1250.
  EXPECT_NEAR(s.nodes[leaf0].volume, 4000, 1e-9);
  EXPECT_NEAR(s.nodes[leaf0 + 1].volume, 1250, 1e-9);
  EXPECT_NEAR(s.nodes[leaf0 + 2].volume, 2750, 1e-9);
  EXPECT_EQ(s.nodes[leaf0].weight, 0.0) << "solid space is not view space";
  EXPECT_NEAR(s.nodes[0].weight, 4000, 1e-9);
  EXPECT_NEAR(s.nodes[0].volume, 8000, 1e-9);
  // A cell straddling the solid boundary counts its non-solid part only.
  EXPECT_NEAR(view_space_volume(s, ConvexPolyhedron::box({{-5, -10, -10}, {5, 10, 10}}, 0)), 2000, 1e-9);
  EXPECT_NEAR(view_space_volume(s, ConvexPolyhedron::box({{1, 1, 1}, {2, 2, 2}}, 0)), 0, 1e-12);
  EXPECT_EQ(q3_view_box(map).hi.x, 0.0);
}

TEST(Q3ViewSpace, ClusterCostsAndAdmittedObjects) {
  const Q3Map map = small_map();
  const Subdivision s = q3_subdivision(map, kBox);
  RawMesh mesh;
  mesh.vertices = {{-1, 0, 0}, {-1, 1, 0}, {-1, 0, 1}, {-2, 0, 0}, {-2, 1, 0}, {-2, 0, 1}};
  mesh.triangles = {{0, 1, 2}, {3, 4, 5}};
  mesh.triangle_group = {0, 1};
  mesh.group_names = {"textures/wall#0", "textures/wall#1"};
  const Scene scene = make_scene(mesh, ObjectGrouping::kGroups, "small");
  std::vector<std::vector<uint32_t>> leaf_pvs(s.nodes.size());
  const size_t leaf0 = map.nodes.size();
  leaf_pvs[leaf0] = {0, 1};  // solid: ignored
  leaf_pvs[leaf0 + 1] = {0};
  leaf_pvs[leaf0 + 2] = {0, 1};
  const Q3ClusterCells cells = q3_cluster_cells(scene, map, s, leaf_pvs, CostModel{});
  EXPECT_NEAR(cells.total_weight, 4000, 1e-9);
  EXPECT_NEAR(cells.cost, (1250.0 * 100 + 2750.0 * 200) / 4000, 1e-9);
  const auto admitted = q3_admitted_objects(scene, map);
  ASSERT_EQ(admitted.size(), 2u);
  EXPECT_EQ(admitted[0], std::vector<uint32_t>({0}));
  EXPECT_EQ(admitted[1], std::vector<uint32_t>({0, 1}));
  // Objects that are not single surfaces cannot be compared.
  RawMesh other = mesh;
  other.group_names = {"a", "b"};
  EXPECT_THROW(q3_object_surfaces(make_scene(other, ObjectGrouping::kGroups, "x"), map), Error);
}

/// oa_dm2 from the fetch script's cache, or "" (the test then skips unless maps are required).
std::string oa_dm2() { return test::oa_dm2_path(VIEWCELLS_DATA_DIR); }

TEST(Q3OaDm2, ClustersCoverTheNonSolidLeaves) {
  const std::string path = oa_dm2();
  if (path.empty()) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  const Q3Map map = read_q3bsp(path);
  ASSERT_EQ(map.cluster_count, 1041);
  std::vector<int> leaves_per_cluster(map.cluster_count, 0);
  size_t open = 0;
  for (const Q3Leaf& l : map.leaves) {
    if (l.cluster < 0) continue;
    ++open;
    ASSERT_LT(l.cluster, map.cluster_count);
    ++leaves_per_cluster[l.cluster];
  }
  EXPECT_GT(open, 0u);
  for (int c = 0; c < map.cluster_count; ++c) EXPECT_GT(leaves_per_cluster[c], 0) << "cluster " << c << " has no leaf";
  // The clusters' volumes add up to the non-solid volume, computed independently by clipping
  // the whole view box down the tree; and random points agree with the map's own walk.
  const Box3 box = q3_view_box(map);
  const Subdivision s = q3_subdivision(map, box);
  const CostModel model;
  const Scene scene = load_scene(path);
  const Q3ClusterCells cells = q3_cluster_cells(scene, map, s, std::vector<std::vector<uint32_t>>(s.nodes.size()), model);
  const double open_volume = view_space_volume(s, ConvexPolyhedron::box(box, 0));
  EXPECT_NEAR(cells.total_weight, open_volume, 1e-9 * open_volume);
  EXPECT_NEAR(s.nodes[0].weight, open_volume, 1e-9 * open_volume);
  Rng rng(3, 0);
  const Vec3 e = box.extent();
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p{box.lo.x + e.x * rng.uniform(), box.lo.y + e.y * rng.uniform(), box.lo.z + e.z * rng.uniform()};
    ASSERT_EQ(q3_leaf_of_node(map, s.locate(p)), map.leaf_at(p));
  }
  expect_columns_find_the_leaves_of_their_points(map, box, 20000);
  // The sky closes the map but costs nothing.
  size_t sky = 0;
  for (const ObjectInfo& o : scene.objects) sky += !o.rendered;
  EXPECT_GT(sky, 0u);
  const std::vector<double> costs = per_object_costs(scene, model);
  for (uint32_t o = 0; o < scene.object_count(); ++o) {
    if (!scene.objects[o].rendered) {
      EXPECT_EQ(costs[o], 0.0) << scene.objects[o].name;
    }
  }
}

TEST(Q3OaDm2, ComparisonRuns) {
  const std::string path = oa_dm2();
  if (path.empty()) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  const Q3Map map = read_q3bsp(path);
  const Scene scene = load_scene(path);
  const auto caster = make_embree_caster(scene);
  CompareConfig config;
  config.methods = {"av-m"};
  config.max_cells = 0;  // three times the clusters
  config.construction.samples = 300000;
  config.evaluation.samples = 300000;
  config.evaluation.seed = 99;
  config.construction.show_progress = config.evaluation.show_progress = config.show_progress = false;
  const Q3Comparison q = compare_with_q3map2(scene, map, *caster, config);
  // Every sample origin was in the non-solid space, so every segment has length there.
  EXPECT_GT(q.ours.construction.rejected_origins, 0u);
  EXPECT_EQ(q.cluster_count, 1041u);
  EXPECT_GT(q.clusters.cost, 0);
  ASSERT_TRUE(std::isfinite(q.avm_cost_at_clusters))
      << q.ours.methods[0].leaves << " cells: " << q.ours.methods[0].stop_reason << "; merged down to "
      << q.ours.av_m->min_cells();
  EXPECT_GT(q.avm_cost_at_clusters, 0);
  EXPECT_GT(q.mean_pvs_ratio, 0);
  EXPECT_EQ(q.q3_row_bytes, 1041u * static_cast<uint64_t>(map.cluster_bytes));
  EXPECT_GT(q.ours_compressed_bytes, 0u);
  uint64_t by_cause = 0;
  for (const auto& [cause, n] : q.excluded_by_cause) by_cause += n;
  EXPECT_EQ(by_cause, q.excluded.size());
  // The view-space weights: AV-M's cells and q3map2's clusters cover the same volume.
  EXPECT_NEAR(q.ours.av_m->total_weight, q.clusters.total_weight, 1e-6 * q.clusters.total_weight);
}

}  // namespace
}  // namespace viewcells
