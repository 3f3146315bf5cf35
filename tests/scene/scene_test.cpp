#include <gtest/gtest.h>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/scene/scene.h"

namespace viewcells {
namespace {

RawMesh two_cubes() {
  RawMesh m;
  test::add_cube(m, {0, 0, 0}, {1, 1, 1}, "a");
  test::add_cube(m, {2, 0, 0}, {3, 1, 1}, "b");
  return m;
}

TEST(Scene, GroupsBecomeObjects) {
  const Scene s = make_scene(two_cubes(), ObjectGrouping::kGroups, "t");
  ASSERT_EQ(s.object_count(), 2u);
  EXPECT_EQ(s.objects[0].name, "a");
  EXPECT_EQ(s.objects[1].name, "b");
  EXPECT_EQ(s.objects[0].triangle_count, 12u);
  EXPECT_TRUE(s.objects[0].solid());
  EXPECT_NEAR(s.objects[0].signed_volume, 1.0, 1e-12);
  EXPECT_NEAR(s.objects[1].surface_area, 6.0, 1e-12);
  EXPECT_TRUE(s.all_solid);
  EXPECT_EQ(s.bounds, (Box3{{0, 0, 0}, {3, 1, 1}}));
}

TEST(Scene, ComponentsAndTriangles) {
  RawMesh m = two_cubes();
  m.group_names.clear();  // a file without groups
  const Scene auto_scene = make_scene(m, ObjectGrouping::kAuto, "t");
  EXPECT_EQ(auto_scene.grouping, ObjectGrouping::kComponents);
  EXPECT_EQ(auto_scene.object_count(), 2u);
  EXPECT_EQ(make_scene(m, ObjectGrouping::kTriangles, "t").object_count(), 24u);
  EXPECT_EQ(make_scene(m, ObjectGrouping::kGroups, "t").object_count(), 1u);
  // Components weld by position: a cube whose faces do not share vertex indices is one piece.
  RawMesh soup;
  for (const auto& tri : m.triangles) {
    if (tri[0] >= 8) break;
    const uint32_t base = static_cast<uint32_t>(soup.vertices.size());
    for (uint32_t v : tri) soup.vertices.push_back(m.vertices[v]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  const Scene welded = make_scene(soup, ObjectGrouping::kComponents, "t");
  EXPECT_EQ(welded.object_count(), 1u);
  EXPECT_TRUE(welded.objects[0].solid()) << "closedness is judged on welded positions";
}

TEST(Scene, DegenerateTrianglesAreDroppedAndCounted) {
  RawMesh m = two_cubes();
  m.triangles.push_back({0, 0, 1});          // repeated vertex
  m.vertices.push_back({0.5, 0, 0});         // collinear with vertices 0 and 1
  m.triangles.push_back({0, 1, static_cast<uint32_t>(m.vertices.size() - 1)});
  m.triangle_group.push_back(0);
  m.triangle_group.push_back(0);
  const Scene s = make_scene(m, ObjectGrouping::kGroups, "t");
  EXPECT_EQ(s.degenerate_dropped, 2u);
  EXPECT_EQ(s.triangle_count(), 24u);
  EXPECT_TRUE(s.objects[0].solid());
}

TEST(Scene, ClosednessAndOrientation) {
  RawMesh open = two_cubes();
  open.triangles.erase(open.triangles.begin());  // a hole in cube a
  open.triangle_group.erase(open.triangle_group.begin());
  Scene s = make_scene(open, ObjectGrouping::kGroups, "t");
  EXPECT_FALSE(s.objects[0].closed);
  EXPECT_FALSE(s.objects[0].solid());
  EXPECT_TRUE(s.objects[1].solid());
  EXPECT_FALSE(s.all_solid);

  RawMesh flipped = two_cubes();
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);  // one face wound the other way
  s = make_scene(flipped, ObjectGrouping::kGroups, "t");
  EXPECT_TRUE(s.objects[0].closed);
  EXPECT_FALSE(s.objects[0].oriented);

  RawMesh inward = two_cubes();
  for (size_t t = 0; t < 12; ++t) std::swap(inward.triangles[t][1], inward.triangles[t][2]);
  s = make_scene(inward, ObjectGrouping::kGroups, "t");
  EXPECT_TRUE(s.objects[0].oriented);
  EXPECT_LT(s.objects[0].signed_volume, 0);
  EXPECT_FALSE(s.objects[0].solid()) << "inward normals would invert the back-face test";
}

TEST(Scene, NonFiniteAndBadIndicesAreErrors) {
  RawMesh m = two_cubes();
  m.vertices[3].y = std::numeric_limits<double>::quiet_NaN();
  try {
    make_scene(m, ObjectGrouping::kGroups, "nan.obj");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nan.obj"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("vertex 4"), std::string::npos);
  }
  RawMesh bad = two_cubes();
  bad.triangles[0][0] = 99;
  EXPECT_THROW(make_scene(bad, ObjectGrouping::kGroups, "t"), Error);
}

TEST(Scene, NonAxisAlignedShareAndTransforms) {
  Scene s = make_scene(two_cubes(), ObjectGrouping::kGroups, "t");
  EXPECT_EQ(s.non_axis_aligned_share(), 0.0);
  const uint64_t before = s.fingerprint();
  rotate_about_z(s, 30.0, {0, 0, 0});
  // Side faces (4 of 6 per cube) are no longer axis-aligned; tops and bottoms still are.
  EXPECT_NEAR(s.non_axis_aligned_share(), 4.0 / 6.0, 1e-9);
  EXPECT_NE(s.fingerprint(), before);
  EXPECT_TRUE(s.all_solid);
  translate(s, {1e5, 1e5, 1e5});
  EXPECT_TRUE(s.all_solid);
  EXPECT_NEAR(s.objects[0].signed_volume, 1.0, 1e-6);
}

TEST(Scene, ParseGrouping) {
  EXPECT_EQ(parse_grouping("components"), ObjectGrouping::kComponents);
  EXPECT_THROW(parse_grouping("bogus"), Error);
}

}  // namespace
}  // namespace viewcells
