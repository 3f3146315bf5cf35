#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <filesystem>
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
  const std::string unknown = test::temp_path("scene.blend");
  test::write_file(unknown, "x");
  expect_load_error(unknown, {"unknown scene format"});
  const std::string one_byte_fbx = test::temp_path("scene.fbx");  // read through Assimp, and refused
  test::write_file(one_byte_fbx, "x");
  expect_load_error(one_byte_fbx, {"not a readable scene"});
}

// A closed unit cube in each mesh format (ASCII, inline so the bytes are visible).
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

TEST(SceneLoader, MeshFormats) {
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
  expect_load_error(garbage, {garbage, "not a PLY file"});
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

/// The cube as binary PLY (either byte order, float coordinates, uchar/int lists, with an
/// extra property and an extra element to skip) and as binary STL.
std::string cube_binary_ply(bool big_endian) {
  RawMesh m;
  test::add_cube(m, {0, 0, 0}, {1, 1, 1}, "cube");
  std::string s = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\ncomment made by a test\nelement vertex " + std::to_string(m.vertices.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face " +
                  std::to_string(m.triangles.size()) +
                  "\nproperty list uchar int vertex_indices\nelement extra 2\nproperty list uchar double values\n"
                  "end_header\n";
  auto put = [&](auto v) {
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    if (big_endian) std::reverse(b, b + sizeof v);
    s.append(b, sizeof v);
  };
  for (const Vec3& v : m.vertices) {
    put(static_cast<float>(v.x)), put(static_cast<float>(v.y)), put(static_cast<float>(v.z));
    put(uint8_t{7});
  }
  for (const auto& t : m.triangles) {
    put(uint8_t{3});
    for (uint32_t v : t) put(static_cast<int32_t>(v));
  }
  for (int e = 0; e < 2; ++e) {
    put(uint8_t{2});
    put(1.5), put(2.5);
  }
  return s;
}

std::string cube_binary_stl() {
  RawMesh m;
  test::add_cube(m, {0, 0, 0}, {1, 1, 1}, "cube");
  std::string s(80, ' ');
  const uint32_t n = static_cast<uint32_t>(m.triangles.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : m.triangles) {
    s.append(12, '\0');
    for (uint32_t v : t)
      for (double c : {m.vertices[v].x, m.vertices[v].y, m.vertices[v].z}) {
        const float f = static_cast<float>(c);
        s.append(reinterpret_cast<const char*>(&f), 4);
      }
    s.append(2, '\0');
  }
  return s;
}

TEST(SceneLoader, BinaryMeshFormats) {
  const std::pair<std::string, std::string> files[] = {{"le.ply", cube_binary_ply(false)},
                                                       {"be.ply", cube_binary_ply(true)},
                                                       {"bin.stl", cube_binary_stl()}};
  for (const auto& [name, bytes] : files) {
    const std::string path = test::temp_path(name);
    test::write_file(path, bytes);
    const Scene s = load_scene(path);
    EXPECT_EQ(s.triangle_count(), 12u) << name;
    ASSERT_EQ(s.object_count(), 1u) << name;
    EXPECT_NEAR(s.objects[0].signed_volume, 1.0, 1e-9) << name;
  }
}

/// Every strict prefix of a mesh file is an error (each format declares what it holds or how
/// it ends), never a smaller mesh, a hang or a crash.
TEST(SceneLoader, EveryTruncationIsAnError) {
  const std::pair<std::string, std::string> files[] = {{"off", kCubeOff},
                                                       {"ply", cube_ply()},
                                                       {"ply", cube_binary_ply(false)},
                                                       {"stl", cube_stl()},
                                                       {"stl", cube_binary_stl()}};
  for (const auto& [ext, bytes] : files) {
    // A trailing newline or the last bytes of "endsolid cube\n" may go without loss.
    const size_t keep = ext == "stl" && bytes[0] == 's' ? bytes.rfind("endsolid") + 8 : bytes.size() - 1;
    for (size_t n = 0; n < keep; ++n) {
      const std::string cut = bytes.substr(0, n);
      const std::string name = "prefix." + ext;
      EXPECT_THROW((ext == "off" ? read_off(cut, name) : ext == "ply" ? read_ply(cut, name) : read_stl(cut, name)),
                   Error)
          << ext << " cut to " << n << " of " << bytes.size() << " bytes";
    }
  }
}

/// What a hostile-input probe found: counts that would allocate or loop without bound, files
/// that invented faces, bytes that are not text. Each is a clear error naming the file.
TEST(SceneLoader, HostileCountsAndBytes) {
  auto expect_error = [](const std::string& name, const std::string& bytes, const std::string& fragment) {
    const std::string path = test::temp_path(name);
    test::write_file(path, bytes);
    expect_load_error(path, {path, fragment});
  };
  const std::string ply_head = "ply\nformat binary_little_endian 1.0\n";
  expect_error("no_end.ply", ply_head + "element vertex 3\nproperty float x\n", "no end_header");
  expect_error("huge_count.ply",
               ply_head + "element vertex 99999999999999999999999\nproperty float x\nproperty float y\n"
                          "property float z\nend_header\n",
               "too large");
  expect_error("big_count.ply",
               ply_head + "element vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\n"
                          "end_header\n" + std::string(24, '\0'),
               "only 24 bytes follow");
  expect_error("no_props.ply", ply_head + "element vertex 1000000000000\nend_header\n", "no properties");
  const std::string list_ply = ply_head +
                               "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                               "element face 1\nproperty list uint int vertex_indices\nend_header\n" +
                               std::string(36, '\0') + std::string("\xff\xff\xff\x7f", 4);
  expect_error("huge_list.ply", list_ply, "list items");
  expect_error("negative.off", "OFF\n-3 1 0\n0 0 0\n", "negative");
  expect_error("many_vertices.off", "OFF\n3000000000 1 0\n0 0 0\n", "only");
  expect_error("huge_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2000000000 0 1 2\n", "line holds 3");
  expect_error("cut_after_header.off", "OFF\n3 1 0\n", "truncated");
  expect_error("invented_faces.off", "OFF\n3 1000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "only");
  expect_error("few_faces.off", "OFF\n3 3 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "truncated");
  expect_error("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "out of range");
  expect_error("bin.off", "OFF BINARY\n", "binary OFF");
  expect_error("short.stl", "abc", "not an STL file");
  std::string random(4096, '\0');
  uint64_t x = 88172645463325252ULL;
  for (char& c : random) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    c = static_cast<char>(x);
  }
  expect_error("random.obj", random, "not a text OBJ");
  expect_error("far.obj", "v 1e39 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n", ":1: coordinate '1e39' is beyond");
  expect_error("overflow.obj", "v 1e400 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n", "out of range");
  expect_error("far.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1e30 0\n3 0 1 2\n", "beyond");
  std::string far_stl = cube_binary_stl();
  const float big = 1e30f;
  std::memcpy(far_stl.data() + 84 + 12, &big, 4);
  expect_error("far.stl", far_stl, "beyond");
  // Not files at all.
  expect_load_error("/dev/null", {"not a regular file"});
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

TEST(ObjReader, SeeThroughMaterialsFromTheMaterialLibrary) {
  // Two quads per group; "pane" is all glass, "wall" mixes: its glass faces are split off.
  const std::string dir = test::temp_path("mtl");
  std::filesystem::create_directories(dir);
  test::write_file(dir + "/m.mtl",
                   "newmtl stone\nKd 0.5 0.5 0.5\nd 1\nnewmtl glass\nd 0.25\nnewmtl tinted\nTr 0.4\n"
                   "newmtl clear\nillum 7\nnewmtl halo\nd -halo 1.0\n");
  const std::string quads = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
  test::write_file(dir + "/s.obj", "mtllib m.mtl\n" + quads +
                                       "o pane\nusemtl glass\nf 1 2 3 4\n"
                                       "o wall\nusemtl stone\nf 5 6 7 8\nusemtl tinted\nf 1 5 8 4\n"
                                       "o lens\nusemtl clear\nf 2 6 7 3\no solid\nusemtl halo\nf 1 2 6 5\n");
  const Scene s = load_scene(dir + "/s.obj");
  std::map<std::string, bool> occludes;
  for (const ObjectInfo& o : s.objects) occludes[o.name] = o.occluder;
  EXPECT_EQ(occludes, (std::map<std::string, bool>{
                          {"pane", false}, {"wall", true}, {"wall (see-through)", false}, {"lens", false}, {"solid", true}}));
  // Without its library the materials are unknown: an error naming the OBJ's line, not opaque glass.
  test::write_file(dir + "/missing.obj", quads + "mtllib nowhere.mtl\no pane\nusemtl glass\nf 1 2 3 4\n");
  expect_load_error(dir + "/missing.obj", {"missing.obj:9:", "nowhere.mtl"});
  test::write_file(dir + "/bad.mtl", "newmtl glass\nd 0.x\n");
  test::write_file(dir + "/bad.obj", "mtllib bad.mtl\n" + quads);
  expect_load_error(dir + "/bad.obj", {"bad.obj:1:", "bad.mtl:2:", "malformed transparency"});
  test::write_file(dir + "/orphan.mtl", "d 0.5\n");
  test::write_file(dir + "/orphan.obj", "mtllib orphan.mtl\n" + quads);
  expect_load_error(dir + "/orphan.obj", {"orphan.mtl:1:", "before any newmtl"});
  // From a stream (no files to read): materials are ignored.
  std::istringstream in("mtllib m.mtl\n" + quads + "o pane\nusemtl glass\nf 1 2 3 4\n");
  EXPECT_TRUE(read_obj(in, "x.obj").group_occluder.empty());
}

TEST(ObjWriter, SeeThroughObjectsRoundTripThroughAMaterialLibrary) {
  const Scene s = generate_scene({GeneratorKind::kGlassCity, 3, 1});
  const size_t glass = std::count_if(s.objects.begin(), s.objects.end(), [](const ObjectInfo& o) { return !o.occluder; });
  ASSERT_GT(glass, 0u);
  const std::string path = test::temp_path("glass.obj");
  write_obj(s, path);
  EXPECT_TRUE(std::filesystem::exists(test::temp_path("glass.mtl")));
  const Scene r = load_scene(path);
  ASSERT_EQ(r.object_count(), s.object_count());
  EXPECT_EQ(r.fingerprint(), s.fingerprint());
  for (size_t i = 0; i < s.object_count(); ++i) {
    EXPECT_EQ(r.objects[i].name, s.objects[i].name);
    EXPECT_EQ(r.objects[i].occluder, s.objects[i].occluder) << s.objects[i].name;
  }
}

}  // namespace
}  // namespace viewcells
