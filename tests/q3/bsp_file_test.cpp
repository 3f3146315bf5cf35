// The Quake 3 BSP reader on small hand-built files, valid and corrupt.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "viewcells/core/error.h"
#include "viewcells/q3/bsp_file.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

/// Writes a BSP file lump by lump.
struct BspBuilder {
  std::string lumps[17];
  int32_t version = 46;

  template <class T>
  static void put(std::string& s, T v) {
    s.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void shader(const std::string& name, int32_t surface, int32_t contents) {
    std::string n = name;
    n.resize(64, '\0');
    lumps[1] += n;
    put(lumps[1], surface);
    put(lumps[1], contents);
  }
  void vertex(float x, float y, float z, float nx = 0, float ny = 0, float nz = 1) {
    for (float f : {x, y, z, 0.f, 0.f, 0.f, 0.f, nx, ny, nz}) put(lumps[10], f);
    put(lumps[10], int32_t{-1});  // colour
  }
  void surface(int32_t shader, int32_t type, int32_t first_vertex, int32_t vertices, int32_t first_index, int32_t indices,
               int32_t pw = 0, int32_t ph = 0) {
    for (int32_t v : {shader, -1, type, first_vertex, vertices, first_index, indices, 0, 0, 0, 0, 0}) put(lumps[13], v);
    for (int k = 0; k < 12; ++k) put(lumps[13], 0.f);
    put(lumps[13], pw);
    put(lumps[13], ph);
  }
  std::string bytes() const {
    std::string out = "IBSP";
    put(out, version);
    int32_t offset = 8 + 8 * 17;
    for (const std::string& l : lumps) {
      put(out, offset);
      put(out, static_cast<int32_t>(l.size()));
      offset += static_cast<int32_t>(l.size());
    }
    for (const std::string& l : lumps) out += l;
    return out;
  }
};

/// A map of two leaves split by z = 0: an opaque quad, a 3x3 patch, a sky quad and a nodraw
/// quad; two clusters, where 0 sees both and 1 sees only itself; one solid caulked brush, the
/// cube [20, 40]^3, in leaf 0.
BspBuilder small_map() {
  BspBuilder b;
  b.lumps[0] = "{\n\"classname\" \"worldspawn\"\n}\n{\n\"classname\" \"info_player_deathmatch\"\n\"origin\" \"8 16 24\"\n}\n";
  b.lumps[0].push_back('\0');
  b.shader("textures/base/wall", 0, kQ3ContentsSolid);
  b.shader("textures/skies/blue", kQ3SurfSky, 0);
  b.shader("textures/common/nodraw", kQ3SurfNodraw, kQ3ContentsSolid);
  b.shader("textures/liquids/water", 0, kQ3ContentsWater);
  for (float f : {0.f, 0.f, 1.f, 0.f}) BspBuilder::put(b.lumps[2], f);  // plane z = 0
  for (int axis = 0; axis < 3; ++axis)  // planes 1-6: the brush's sides, +axis at 40, -axis at 20
    for (float sign : {1.f, -1.f}) {
      for (int k = 0; k < 3; ++k) BspBuilder::put(b.lumps[2], k == axis ? sign : 0.f);
      BspBuilder::put(b.lumps[2], sign > 0 ? 40.f : -20.f);
    }
  for (int32_t side = 0; side < 6; ++side) {  // brush sides: plane, shader (nodraw)
    BspBuilder::put(b.lumps[9], side + 1);
    BspBuilder::put(b.lumps[9], int32_t{2});
  }
  for (int32_t v : {0, 6, 0}) BspBuilder::put(b.lumps[8], v);  // the brush: sides 0-5, solid shader
  BspBuilder::put(b.lumps[6], int32_t{0});                     // leaf 0 holds brush 0
  for (int32_t v : {0, -1, -2, -64, -64, -64, 64, 64, 64}) BspBuilder::put(b.lumps[3], v);  // node
  for (int32_t cluster : {0, 1}) {  // leaves: cluster, area, mins, maxs, surfaces, brushes
    for (int32_t v : {cluster, 0, -64, -64, cluster ? -64 : 0, 64, 64, cluster ? 0 : 64, 0, 2, 0, cluster ? 0 : 1})
      BspBuilder::put(b.lumps[4], v);
  }
  for (int32_t s : {0, 1}) BspBuilder::put(b.lumps[5], s);
  // The world model: mins, maxs, first surface, surfaces, brushes.
  for (float f : {-64.f, -64.f, -64.f, 64.f, 64.f, 64.f}) BspBuilder::put(b.lumps[7], f);
  for (int32_t v : {0, 5, 0, 1}) BspBuilder::put(b.lumps[7], v);
  // Quads: 4 vertices each, indices 0 2 1, 0 3 2 (clockwise seen from +z, as Quake 3 writes).
  auto quad = [&](float z) {
    b.vertex(0, 0, z), b.vertex(10, 0, z), b.vertex(10, 10, z), b.vertex(0, 10, z);
  };
  quad(5);   // vertices 0-3: opaque
  quad(50);  // 4-7: sky
  quad(20);  // 8-11: nodraw
  quad(30);  // 12-15: water
  for (int32_t i : {0, 2, 1, 0, 3, 2}) BspBuilder::put(b.lumps[11], i);
  for (int j = 0; j < 3; ++j)  // 16-24: a flat 3x3 patch at z = 7
    for (int i = 0; i < 3; ++i) b.vertex(5.f * i, 5.f * j, 7);
  b.surface(0, 1, 0, 4, 0, 6);
  b.surface(0, 2, 16, 9, 0, 0, 3, 3);
  b.surface(1, 1, 4, 4, 0, 6);
  b.surface(2, 1, 8, 4, 0, 6);
  b.surface(3, 1, 12, 4, 0, 6);
  for (int32_t v : {2, 1}) BspBuilder::put(b.lumps[16], v);
  b.lumps[16].push_back(0x3);  // cluster 0 sees 0 and 1
  b.lumps[16].push_back(0x2);  // cluster 1 sees 1
  return b;
}

TEST(Q3Bsp, ReadsAHandBuiltMap) {
  const Q3Map m = parse_q3bsp(small_map().bytes(), "small.bsp");
  EXPECT_EQ(m.version, 46);
  ASSERT_EQ(m.shaders.size(), 4u);
  EXPECT_EQ(m.shaders[1].name, "textures/skies/blue");
  ASSERT_EQ(m.surfaces.size(), 5u);
  EXPECT_EQ(m.kind(m.surfaces[0]), Q3SurfaceKind::kOpaque);
  EXPECT_EQ(m.kind(m.surfaces[2]), Q3SurfaceKind::kSky);
  EXPECT_EQ(m.kind(m.surfaces[3]), Q3SurfaceKind::kSkipped);
  EXPECT_EQ(m.kind(m.surfaces[4]), Q3SurfaceKind::kNonOccluding);
  EXPECT_EQ(m.cluster_count, 2);
  EXPECT_TRUE(m.cluster_sees(0, 1));
  EXPECT_FALSE(m.cluster_sees(1, 0));
  EXPECT_EQ(m.leaves[m.leaf_at({1, 1, 10})].cluster, 0);
  EXPECT_EQ(m.leaves[m.leaf_at({1, 1, -10})].cluster, 1);
  const std::vector<Vec3> spawns = q3_spawn_points(m);
  ASSERT_EQ(spawns.size(), 1u);
  EXPECT_EQ(spawns[0], (Vec3{8, 16, 24}));

  Q3MeshStats st;
  Q3MeshOptions options;
  options.patch_level = 2;
  const RawMesh mesh = q3_world_mesh(m, options, &st);
  EXPECT_EQ(st.surfaces[static_cast<int>(Q3SurfaceKind::kOpaque)], 2u);
  EXPECT_EQ(st.patches, 1u);
  EXPECT_EQ(st.spawn_points, 1u);
  // Opaque quad 2 + patch (2x2 pieces of... one 3x3 piece at level 2: 8) + sky 2.
  EXPECT_EQ(st.brush_hulls, 1u);
  // Opaque quad, patch, sky, water, and the brush hull: 6 faces of 2 triangles.
  EXPECT_EQ(mesh.triangles.size(), 2u + 8u + 2u + 2u + 12u);
  EXPECT_EQ(mesh.group_names.size(), 5u);
  EXPECT_EQ(mesh.group_rendered, std::vector<uint8_t>({1, 1, 0, 1, 0})) << "neither the sky nor the hulls are rendered";
  EXPECT_EQ(mesh.group_occluder, std::vector<uint8_t>({1, 1, 1, 0, 1})) << "water is seen through";
  // Every surface triangle faces +z, as the vertex normals say: winding turned counter-clockwise.
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (mesh.triangle_group[i] == 4) continue;  // the hull
    const auto& t = mesh.triangles[i];
    const Vec3 n = cross(mesh.vertices[t[1]] - mesh.vertices[t[0]], mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    EXPECT_GT(n.z, 0);
  }
  options.sky = false;
  options.brush_hulls = false;
  options.see_through = false;
  EXPECT_EQ(q3_world_mesh(m, options).triangles.size(), 10u) << "without the sky, the water and the hulls";
  options.hull_inset = 10;  // thinner than twice the inset: nothing left
  options.brush_hulls = true;
  EXPECT_EQ(q3_world_mesh(m, options).triangles.size(), 10u);
}

TEST(Q3Bsp, LoadsAsAScene) {
  const std::string path = (std::filesystem::temp_directory_path() / "viewcells_q3_small.bsp").string();
  {
    std::ofstream out(path, std::ios::binary);
    out << small_map().bytes();
  }
  const Scene s = load_scene(path);
  EXPECT_EQ(s.object_count(), 5u);
  EXPECT_EQ(s.triangle_count(), 2u + 32u + 2u + 2u + 12u) << "patches at level 4 in scenes";
  EXPECT_FALSE(s.objects[3].occluder) << "water";
  EXPECT_TRUE(s.objects[3].rendered);
  // The brush hull: a closed, outward box half a unit inside the brush, occluding, not rendered.
  const ObjectInfo& hull = s.objects[4];
  EXPECT_EQ(hull.name, "solid brushes");
  EXPECT_FALSE(hull.rendered);
  EXPECT_TRUE(hull.solid());
  EXPECT_EQ(hull.bounds.lo, (Vec3{20.5, 20.5, 20.5}));
  EXPECT_EQ(hull.bounds.hi, (Vec3{39.5, 39.5, 39.5}));
  EXPECT_TRUE(s.objects[0].rendered);
  std::filesystem::remove(path);
}

void expect_rejected(const std::string& bytes, const std::string& fragment) {
  try {
    parse_q3bsp(bytes, "bad.bsp");
    ADD_FAILURE() << "accepted; expected an error with '" << fragment << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.bsp"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Q3Bsp, RejectsCorruptFiles) {
  const std::string good = small_map().bytes();
  expect_rejected(good.substr(0, good.size() - 7), "outside the file");
  expect_rejected("IBSX" + good.substr(4), "no IBSP header");
  expect_rejected(good.substr(0, 20), "header ends early");
  BspBuilder b = small_map();
  b.version = 38;
  expect_rejected(b.bytes(), "version 38");
  b = small_map();
  b.lumps[3].replace(4, 4, std::string("\x07\x00\x00\x00", 4));  // node child 7 does not exist
  expect_rejected(b.bytes(), "child that does not exist");
  b = small_map();
  b.lumps[11].replace(4, 4, std::string("\x09\x00\x00\x00", 4));  // index 9 of a 4-vertex quad
  expect_rejected(b.bytes(), "indexes a vertex it does not own");
  b = small_map();
  b.lumps[16].pop_back();  // a visibility row cut short
  expect_rejected(b.bytes(), "cluster rows");
  b = small_map();
  b.lumps[13].replace(104 + 96, 4, std::string("\x04\x00\x00\x00", 4));  // a patch 4 wide
  expect_rejected(b.bytes(), "malformed control grid");
  b = small_map();
  b.lumps[2].pop_back();  // planes not a whole number of records
  expect_rejected(b.bytes(), "whole number");
  b = small_map();
  b.lumps[9].replace(0, 4, std::string("\x63\x00\x00\x00", 4));  // a brush side on plane 99
  expect_rejected(b.bytes(), "brush side 0 names a missing plane");
  b = small_map();
  b.lumps[8].replace(4, 4, std::string("\x07\x00\x00\x00", 4));  // 7 sides of 6
  expect_rejected(b.bytes(), "brush 0 has sides outside");
  b = small_map();
  b.lumps[6].replace(0, 4, std::string("\x05\x00\x00\x00", 4));  // leaf brush 5 of 1
  expect_rejected(b.bytes(), "missing brush");
}

}  // namespace
}  // namespace viewcells
