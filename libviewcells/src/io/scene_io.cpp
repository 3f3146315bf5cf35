// load_scene (io/scene_io.h): the reader a file's extension names (OBJ, PLY, OFF, STL, through
// Assimp glTF, FBX and the others, or a format a front end registered, such as a Quake 3 map),
// the coordinates checked, and the scene made. The readers themselves live in obj_io.cpp,
// mesh_io.cpp and assimp_io.cpp (and q3/bsp_file.cpp, registered).
#include "viewcells/io/scene_io.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/registry.h"

namespace viewcells {

namespace {
ExtensionRegistry<SceneFormat>& formats() {
  static ExtensionRegistry<SceneFormat> f;
  return f;
}
}  // namespace

void register_scene_format(SceneFormat format) { formats().add(std::move(format), "register_scene_format"); }

std::optional<SceneFormat> registered_scene_format(const std::string& path) {
  return formats().find(lower_extension(path));
}

Scene load_scene(const std::string& path, ObjectGrouping grouping) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(path, 0, "no such file");
  if (std::filesystem::is_directory(path, ec)) throw Error(path, 0, "is a directory, not a scene file");
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path, 0, "not a regular file");
  const std::string ext = lower_extension(path);
  const bool assimp = is_assimp_extension(ext);
  if (!assimp && (grouping == ObjectGrouping::kNodes || grouping == ObjectGrouping::kMeshes))
    throw Error(path, 0, std::string("--objects ") + to_string(grouping) +
                             " applies to scene-graph formats read through Assimp (glTF, FBX, ...), not to '" + ext +
                             "' files");
  RawMesh mesh;
  if (assimp) {
    mesh = read_assimp(path, grouping == ObjectGrouping::kMeshes ? AssimpObjects::kMeshes : AssimpObjects::kNodes);
    if (grouping == ObjectGrouping::kAuto || grouping == ObjectGrouping::kGroups) grouping = ObjectGrouping::kNodes;
  } else if (ext == ".obj") {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path, 0, "cannot open file");
    mesh = read_obj(in, path, [&](const std::string& file) {
      const std::filesystem::path mtl = std::filesystem::path(path).parent_path() / file;
      std::ifstream m(mtl, std::ios::binary);
      if (!m) throw Error("cannot open " + mtl.string() + " (without it, see-through materials are unknown)");
      return read_all(m, mtl.string());
    });
  } else if (ext == ".ply") {
    mesh = read_ply(read_file_bytes(path), path);
  } else if (ext == ".off") {
    mesh = read_off(read_file_bytes(path), path);
  } else if (ext == ".stl") {
    mesh = read_stl(read_file_bytes(path), path);
  } else if (const std::optional<SceneFormat> registered = registered_scene_format(path)) {
    mesh = registered->read(path);
  } else if (ext == ".bsp") {
    throw Error(path, 0, "a Quake 3 map, but no reader for .bsp was registered (a front end calls "
                         "register_q3_map_format(), q3/bsp_file.h)");
  } else {
    throw Error(path, 0, "unknown scene format '" + ext +
                             "' (expected .obj, .ply, .off, .stl, .bsp, or through Assimp .gltf, .glb, .fbx, .dae, "
                             ".3ds, .x, .ase, .lwo, .ms3d)");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {  // binary files (text readers say the line)
    const Vec3& v = mesh.vertices[i];
    if (!(std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}) <= kMaxCoordinate))
      throw Error(path, 0, "vertex " + std::to_string(i) + " lies beyond what ray casting can represent (coordinates "
                           "at most 1e18 in magnitude)");
  }
  Scene scene = make_scene(std::move(mesh), grouping, path);
  if (scene.triangles.empty())
    throw Error(path, 0, scene.degenerate_dropped
                             ? "all " + std::to_string(scene.degenerate_dropped) + " triangles are degenerate"
                             : "the scene has no triangles");
  return scene;
}

}  // namespace viewcells
