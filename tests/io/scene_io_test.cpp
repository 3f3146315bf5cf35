#include <gtest/gtest.h>

#include <sstream>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

/// Expects load_scene(path) to throw an Error whose message contains every fragment.
void expect_load_error(const std::string& path, std::initializer_list<std::string> fragments) {
  try {
    load_scene(path);
    FAIL() << "no error for " << path;
  } catch (const Error& e) {
    for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
  }
}

const char* kCubeObjGroups = R"(# two groups, one split over two statements
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
o bottom_and_top
f 1 3 4 2
f 5 6 8 7
g sides
f 1 2 6 5
f 3 7 8 4
o bottom_and_top
f -8 -4 -2 -6
f 2/1 4/2 8/3 6/4
)";

TEST(ObjReader, GroupsBecomeObjects) {
  const std::string path = test::temp_path("groups.obj");
  test::write_file(path, kCubeObjGroups);
  const Scene s = load_scene(path);
  ASSERT_EQ(s.object_count(), 2u);
  EXPECT_EQ(s.objects[0].name, "bottom_and_top");
  EXPECT_EQ(s.objects[1].name, "sides");
  EXPECT_EQ(s.objects[0].triangle_count, 8u);  // incl. the faces with negative and slashed indices
  EXPECT_EQ(s.objects[1].triangle_count, 4u);
  EXPECT_EQ(s.grouping, ObjectGrouping::kGroups);
  const Scene comps = load_scene(path, ObjectGrouping::kComponents);
  ASSERT_EQ(comps.object_count(), 1u);
  EXPECT_TRUE(comps.objects[0].solid());
  EXPECT_EQ(load_scene(path, ObjectGrouping::kTriangles).object_count(), 12u);
}

TEST(ObjReader, FacesBeforeFirstGroupGoToDefault) {
  std::istringstream in("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng later\nf 1 3 2\n");
  const RawMesh m = read_obj(in, "x.obj");
  ASSERT_EQ(m.group_names.size(), 2u);
  EXPECT_EQ(m.group_names[m.triangle_group[0]], "default");
  EXPECT_EQ(m.group_names[m.triangle_group[1]], "later");
}

TEST(ObjReader, ErrorsNameFileAndLine) {
  const std::string nan_path = test::temp_path("nan.obj");
  test::write_file(nan_path, "v 0 0 0\nv 1 0 0\n# comment\nv 0 nan 0\nf 1 2 3\n");
  expect_load_error(nan_path, {nan_path + ":4:", "NaN or infinite"});
  const std::string inf_path = test::temp_path("inf.obj");
  test::write_file(inf_path, "v 0 0 0\nv 1 0 -inf\nv 0 1 0\nf 1 2 3\n");
  expect_load_error(inf_path, {inf_path + ":2:"});
  const std::string bad_number = test::temp_path("bad_number.obj");
  test::write_file(bad_number, "v 0 0 0\nv 1 0x 0\n");
  expect_load_error(bad_number, {":2:", "malformed coordinate"});
  const std::string short_vertex = test::temp_path("short.obj");
  test::write_file(short_vertex, "v 0 0\n");
  expect_load_error(short_vertex, {":1:", "three coordinates"});
  const std::string bad_index = test::temp_path("bad_index.obj");
  test::write_file(bad_index, "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 7\n");
  expect_load_error(bad_index, {":5:", "out of range"});
  const std::string two_vertex_face = test::temp_path("two.obj");
  test::write_file(two_vertex_face, "v 0 0 0\nv 1 0 0\nf 1 2\n");
  expect_load_error(two_vertex_face, {":3:", "at least three"});
}

TEST(SceneLoader, EmptyMissingAndUnknownFilesAreErrors) {
  const std::string empty = test::temp_path("empty.obj");
  test::write_file(empty, "");
  expect_load_error(empty, {"no triangles"});
  const std::string flat = test::temp_path("degenerate.obj");
  test::write_file(flat, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  expect_load_error(flat, {"degenerate"});
  expect_load_error(test::temp_path("missing.obj"), {"no such file"});
  const std::string unknown = test::temp_path("scene.fbx");
  test::write_file(unknown, "x");
  expect_load_error(unknown, {"unknown scene format"});
}

// A closed unit cube in each OpenMesh format (ASCII, inline so the bytes are visible).
const char* kCubeOff = R"(OFF
8 6 0
0 0 0
1 0 0
0 1 0
1 1 0
0 0 1
1 0 1
0 1 1
1 1 1
4 0 2 3 1
4 4 5 7 6
4 0 1 5 4
4 2 6 7 3
4 0 4 6 2
4 1 3 7 5
)";

std::string cube_ply() {
  std::string s = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
  std::string off = kCubeOff;
  s += off.substr(off.find("0 0 0\n"));
  return s;
}

std::string cube_stl() {
  RawMesh m;
  test::add_cube(m, {0, 0, 0}, {1, 1, 1}, "cube");
  std::ostringstream s;
  s << "solid cube\n";
  for (const auto& t : m.triangles) {
    s << " facet normal 0 0 0\n  outer loop\n";
    for (uint32_t v : t) s << "   vertex " << m.vertices[v].x << ' ' << m.vertices[v].y << ' ' << m.vertices[v].z << '\n';
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid cube\n";
  return s.str();
}

TEST(SceneLoader, MeshFormatsThroughOpenMesh) {
  const std::pair<std::string, std::string> files[] = {
      {"cube.off", kCubeOff}, {"cube.ply", cube_ply()}, {"cube.stl", cube_stl()}};
  for (const auto& [name, text] : files) {
    const std::string path = test::temp_path(name);
    test::write_file(path, text);
    const Scene s = load_scene(path);
    EXPECT_EQ(s.triangle_count(), 12u) << name;
    ASSERT_EQ(s.object_count(), 1u) << name;  // no groups: one connected component
    EXPECT_TRUE(s.objects[0].solid()) << name;
    EXPECT_NEAR(s.objects[0].signed_volume, 1.0, 1e-9) << name;
  }
}

TEST(SceneLoader, MeshFormatErrors) {
  std::string off = kCubeOff;
  off.replace(off.find("1 1 0\n"), 5, "1 nan 0");
  const std::string nan_off = test::temp_path("nan.off");
  test::write_file(nan_off, off);
  expect_load_error(nan_off, {nan_off + ":6:", "NaN"});
  const std::string garbage = test::temp_path("garbage.ply");
  test::write_file(garbage, "this is not a ply file\n");
  expect_load_error(garbage, {garbage, "could not parse"});
  const std::string truncated = test::temp_path("truncated.off");
  test::write_file(truncated, std::string(kCubeOff).substr(0, 60));
  expect_load_error(truncated, {truncated, "truncated"});
  const std::string truncated_ply = test::temp_path("truncated.ply");
  test::write_file(truncated_ply, cube_ply().substr(0, cube_ply().size() - 20));
  expect_load_error(truncated_ply, {truncated_ply, "truncated"});
  const std::string truncated_stl = test::temp_path("truncated.stl");
  test::write_file(truncated_stl, cube_stl().substr(0, cube_stl().size() - 40));
  expect_load_error(truncated_stl, {truncated_stl, "truncated"});
  // Binary STL: 80-byte header, count, 50 bytes per triangle; cut in the middle of one.
  std::string binary(80, ' ');
  const uint32_t count = 2;
  binary.append(reinterpret_cast<const char*>(&count), 4);
  binary.append(70, '\0');
  const std::string truncated_bin = test::temp_path("truncated_bin.stl");
  test::write_file(truncated_bin, binary);
  expect_load_error(truncated_bin, {truncated_bin});
}

TEST(ObjWriter, RoundTripsExactly) {
  const Scene s = generate_scene({GeneratorKind::kRotatedOffice, 5, 1});
  const std::string path = test::temp_path("roundtrip.obj");
  write_obj(s, path);
  const Scene r = load_scene(path);
  ASSERT_EQ(r.object_count(), s.object_count());
  ASSERT_EQ(r.triangle_count(), s.triangle_count());
  EXPECT_EQ(r.vertices, s.vertices) << "coordinates survive the text round trip bit for bit";
  EXPECT_EQ(r.fingerprint(), s.fingerprint());
  for (size_t i = 0; i < s.object_count(); ++i) EXPECT_EQ(r.objects[i].name, s.objects[i].name);
}

}  // namespace
}  // namespace viewcells
