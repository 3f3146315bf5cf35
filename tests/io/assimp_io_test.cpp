// Scenes through Assimp: a glTF file written here (instances, transforms, names, a see-through
// material) and real files from Debian's assimp-testmodels; broken files are rejected.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

const std::string kModels = "/usr/share/assimp/models/";

std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= uint8_t(bytes[i + 2]);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? k[v & 63] : '=';
  }
  return out;
}

/// A glTF 2.0 file: one unit cube mesh (y-up) instanced by nodes "left" (at x = -2) and
/// "right" (at x = +2, scaled by 2 along y), and node "glass" with the same cube under an
/// alpha-blended material, a child of "right" (so at x = +2 + 0, y-scaled, then moved up 3).
/// `first_x`: the first vertex's x (NaN or infinity for a broken file).
std::string cube_gltf(const std::string& alpha_mode = "BLEND", float first_x = 0) {
  const float p[8][3] = {{first_x, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  const uint16_t idx[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  std::string buffer(reinterpret_cast<const char*>(p), sizeof p);
  buffer.append(reinterpret_cast<const char*>(idx), sizeof idx);
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],
 "nodes":[{"name":"left","mesh":0,"translation":[-2,0,0]},
          {"name":"right","mesh":0,"translation":[2,0,0],"scale":[1,2,1],"children":[2]},
          {"name":"glass","mesh":1,"translation":[0,3,0]}],
 "meshes":[{"name":"cube","primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]},
           {"name":"pane","primitives":[{"attributes":{"POSITION":0},"indices":1,"material":1}]}],
 "materials":[{"name":"stone"},{"name":"glass","alphaMode":")" +
         alpha_mode + R"(","pbrMetallicRoughness":{"baseColorFactor":[1,1,1,0.3]}}],
 "buffers":[{"byteLength":168,"uri":"data:application/octet-stream;base64,)" +
         base64(buffer) + R"("}],
 "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":96},{"buffer":0,"byteOffset":96,"byteLength":72}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[0,0,0],"max":[1,1,1]},
              {"bufferView":1,"componentType":5123,"count":36,"type":"SCALAR"}]})";
}

std::string write_temp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("viewcells_assimp_" + name);
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

const ObjectInfo& object_named(const Scene& s, const std::string& name) {
  for (const ObjectInfo& o : s.objects)
    if (o.name == name) return o;
  throw std::runtime_error("no object " + name);
}

TEST(AssimpIo, GltfNodesAreObjectsWithTransformsInstancesAndSeeThroughMaterials) {
  const Scene s = load_scene(write_temp("cubes.gltf", cube_gltf()));
  EXPECT_EQ(s.grouping, ObjectGrouping::kNodes);
  ASSERT_EQ(s.object_count(), 3u);
  EXPECT_EQ(s.triangle_count(), 36u);
  const ObjectInfo& left = object_named(s, "left");
  const ObjectInfo& right = object_named(s, "right");
  const ObjectInfo& glass = object_named(s, "glass (see-through)");
  // glTF's y is up; viewcells' z: (x, y, z) -> (x, -z, y).
  EXPECT_NEAR(left.bounds.lo.x, -2, 1e-9);
  EXPECT_NEAR(left.bounds.hi.x, -1, 1e-9);
  EXPECT_NEAR(left.bounds.lo.y, -1, 1e-9);
  EXPECT_NEAR(left.bounds.hi.z, 1, 1e-9);
  EXPECT_NEAR(right.bounds.lo.x, 2, 1e-9);
  EXPECT_NEAR(right.bounds.hi.z, 2, 1e-9);  // scaled by 2 along glTF's y, which is up
  // The child: its parent's transform applies to its own (y + 3, then the parent's y scale).
  EXPECT_NEAR(glass.bounds.lo.z, 6, 1e-9);
  EXPECT_NEAR(glass.bounds.hi.z, 8, 1e-9);
  for (const ObjectInfo* o : {&left, &right}) {
    EXPECT_TRUE(o->occluder);
    EXPECT_TRUE(o->solid()) << o->name;  // a transform keeps a closed, outward cube so
  }
  EXPECT_FALSE(glass.occluder);
  EXPECT_TRUE(glass.rendered);
}

TEST(AssimpIo, MeshesGroupingAndTheOtherGroupingsApply) {
  const std::string path = write_temp("cubes2.gltf", cube_gltf("MASK"));
  const Scene meshes = load_scene(path, ObjectGrouping::kMeshes);
  EXPECT_EQ(meshes.grouping, ObjectGrouping::kMeshes);
  ASSERT_EQ(meshes.object_count(), 3u);
  EXPECT_FALSE(object_named(meshes, "glass/pane").occluder);  // alpha-tested: seen through too
  EXPECT_EQ(load_scene(path, ObjectGrouping::kTriangles).object_count(), 36u);
  EXPECT_EQ(load_scene(path, ObjectGrouping::kComponents).object_count(), 3u);
  const Scene opaque = load_scene(write_temp("cubes3.gltf", cube_gltf("OPAQUE")));
  // OPAQUE ignores the base colour's alpha (glTF 2.0, 3.9.4), though Assimp reports it as the
  // opacity: all three occlude.
  for (const ObjectInfo& o : opaque.objects) EXPECT_TRUE(o.occluder) << o.name;
  EXPECT_EQ(opaque.object_count(), 3u);
}

TEST(AssimpIo, NodesAndMeshesApplyOnlyToSceneGraphFormats) {
  const std::string obj = write_temp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THROW(load_scene(obj, ObjectGrouping::kNodes), Error);
  EXPECT_THROW(load_scene(obj, ObjectGrouping::kMeshes), Error);
  EXPECT_EQ(parse_grouping("nodes"), ObjectGrouping::kNodes);
  EXPECT_STREQ(to_string(ObjectGrouping::kMeshes), "meshes");
}

TEST(AssimpIo, RealFilesFromAssimpTestModels) {
  ASSERT_TRUE(std::filesystem::exists(kModels)) << "install assimp-testmodels (scripts/install-deps.sh)";
  const Scene engine = load_scene(kModels + "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  EXPECT_GT(engine.triangle_count(), 100000u);
  EXPECT_GT(engine.object_count(), 50u);
  const Scene cubes = load_scene(kModels + "FBX/cubes_with_names.fbx");
  EXPECT_EQ(cubes.object_count(), 4u);
  for (const ObjectInfo& o : cubes.objects) EXPECT_TRUE(o.closed) << o.name;
  const Scene duck = load_scene(kModels + "Collada/duck.dae");
  EXPECT_GT(duck.triangle_count(), 1000u);
  // Clear-coat samples: one of its materials is alpha-blended.
  const Scene coat = load_scene(kModels + "glTF2/ClearCoat-glTF/ClearCoatTest.gltf");
  int see_through = 0;
  for (const ObjectInfo& o : coat.objects) see_through += !o.occluder;
  EXPECT_GE(see_through, 1);
}

void expect_error(const std::string& path, const std::string& fragment) {
  try {
    load_scene(path);
    FAIL() << "no error for " << path;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

/// `text` with every `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

TEST(AssimpIo, WhatAssimpWouldDropOrCrashOnIsAnErrorSayingWhy) {
  // A NaN or infinite vertex: the mesh was dropped without a word (Assimp's FindInvalidData),
  // where the OBJ reader names it; now both do. A file of NaNs alone said "No meshes remaining".
  for (float bad : {NAN, INFINITY, -INFINITY})
    expect_error(write_temp("nan.gltf", cube_gltf("BLEND", bad)), "mesh 'cube' has a vertex (0) whose coordinates are not finite");
  // Lines and points only: no triangles, said so.
  expect_error(write_temp("lines.gltf", replaced(cube_gltf(), R"("indices":1,)", R"("indices":1,"mode":1,)")),
               "holds no triangles (only points or lines");
  // A valid file whose node chain is deeper than Assimp's stack takes (it crashed in Assimp,
  // "malformed"): refused before Assimp, saying it is a limit.
  std::string chain = R"("nodes":[)";
  for (int i = 0; i < 20000; ++i) chain += R"({"name":"n)" + std::to_string(i) + R"(","children":[)" + std::to_string(i + 1) + "]},";
  chain += R"({"name":"leaf","mesh":0}],)";
  std::string deep = cube_gltf();
  const size_t from = deep.find(R"("nodes":[{"name":"left")"), to = deep.find(R"("meshes")");
  deep.replace(from, to - from, chain);
  deep = replaced(deep, R"("scenes":[{"nodes":[0,1]}])", R"("scenes":[{"nodes":[0]}])");
  expect_error(write_temp("deep.gltf", deep), "more than the 256 levels viewcells reads");
  // Assimp's messages quote bytes of the file: binary ones are shown as \xNN, never raw. A
  // binary FBX whose one node has a property of type code 0xfe: "unexpected type code: \xfe".
  std::string fbx = std::string("Kaydara FBX Binary  \0\x1a\0", 23) + std::string("\xe8\x1c\0\0", 4);
  const std::string name = "Objects", property = "\xfe\x01\x02\x03\x04";
  const uint32_t record[3] = {static_cast<uint32_t>(27 + 13 + name.size() + property.size()), 1,
                              static_cast<uint32_t>(property.size())};
  fbx.append(reinterpret_cast<const char*>(record), sizeof record);
  fbx += static_cast<char>(name.size());
  fbx += name + property + std::string(213, '\0');
  try {
    load_scene(write_temp("binary.fbx", fbx));
    FAIL() << "no error for a broken FBX";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("type code: \\xfe"), std::string::npos) << what;
    for (unsigned char ch : what) EXPECT_TRUE(ch >= 0x20 && ch < 0x7f) << what;
  }
}

TEST(AssimpIo, BrokenFilesAreErrorsNamingTheFile) {
  expect_error(kModels + "glTF2/IndexOutOfRange/IndexOutOfRange.gltf", "out-of-range");
  expect_error(kModels + "glTF2/RecursiveNodes/RecursiveNodes.gltf", "the node tree has a cycle");
  expect_error(kModels + "glTF2/MissingBin/BoxTextured.gltf", "BoxTextured0.bin");
  expect_error(kModels + "glTF2/TestNoRootNode/NoScene.gltf", "not a readable scene");
  // Truncated binary glTF and FBX, at several lengths.
  for (const std::string& real :
       {kModels + "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", kModels + "FBX/cubes_with_names.fbx"}) {
    std::ifstream in(real, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 1000u);
    const std::string ext = std::filesystem::path(real).extension().string();
    for (double share : {0.0, 0.01, 0.5, 0.9}) {
      const std::string cut = bytes.substr(0, static_cast<size_t>(share * bytes.size()));
      EXPECT_THROW(load_scene(write_temp("cut" + ext, cut)), Error) << real << " cut at " << share;
      EXPECT_THROW(read_assimp_bytes(cut, ext, AssimpObjects::kNodes, "memory" + ext), Error);
    }
  }
  expect_error(write_temp("garbage.glb", std::string(4096, '\x7f')), "broken glTF");
  // Assimp reads in a child process: where it crashes (a null dereference the fuzzer found in
  // its glTF importer), the file is an error here.
  expect_error(std::string(VIEWCELLS_DATA_DIR) + "/fuzz/regressions/glb/crash-null-deref.glb", "Assimp crashed");
  // Declared sizes beyond the file are refused before Assimp allocates them.
  std::string glb;
  {
    std::ifstream in(kModels + "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", std::ios::binary);
    glb.assign((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  std::string huge = glb;
  const uint32_t two_gb = 0x80000000u;
  std::memcpy(huge.data() + 8, &two_gb, 4);
  expect_error(write_temp("huge.glb", huge), "declares 2147483648 bytes");
  const std::string big_buffer = std::string(cube_gltf()).replace(cube_gltf().find("\"byteLength\":168"), 16,
                                                                   "\"byteLength\":999999999");
  expect_error(write_temp("big.gltf", big_buffer), "a buffer declares 999999999 bytes");
}

// A glTF's external files must lie in its folder (issue 67): a level from an untrusted source
// may not read the baking machine's files. The same file reads when its buffer is beside it.
TEST(AssimpIo, ExternalFilesOutsideTheFoldersAreRefused) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "viewcells_gltf_uris";
  fs::remove_all(root);
  fs::create_directories(root / "level");
  const std::string model = kModels + "glTF2/BoxTextured-glTF/";
  fs::copy_file(model + "BoxTextured0.bin", root / "level" / "BoxTextured0.bin");
  fs::copy_file(model + "BoxTextured0.bin", root / "secret.bin");
  std::ifstream in(model + "BoxTextured.gltf");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto with_uri = [&](const std::string& uri) {
    const fs::path p = root / "level" / "level.gltf";
    std::ofstream(p) << replaced(text, R"("uri": "BoxTextured0.bin")", "\"uri\": \"" + uri + "\"");
    return p.string();
  };
  EXPECT_GT(load_scene(with_uri("BoxTextured0.bin")).triangle_count(), 0u);
  for (const std::string uri : {"../secret.bin", "%2e%2e/secret.bin", "/etc/passwd", "file:///etc/passwd",
                                "./../level/../../secret.bin"})
    expect_error(with_uri(uri), "is outside the file's folder");
  fs::create_directory_symlink(root, root / "level" / "up");
  expect_error(with_uri("up/secret.bin"), "is outside the file's folder");
  fs::remove_all(root);
}

}  // namespace
}  // namespace viewcells
