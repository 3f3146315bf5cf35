#pragma once
/// Scene files: OBJ (keeps `o`/`g` groups), PLY (ASCII and binary), OFF (ASCII) and STL
/// (ASCII and binary), as raw triangles without manifold repair, and an OBJ writer. These
/// readers are our own and strict: errors name the file and, in text, the line; declared counts
/// are checked against the bytes left before anything is allocated; a truncated file is an
/// error, never a shorter or invented mesh. glTF 2.0 (.gltf, .glb), FBX and a few more formats
/// of the tools artists use are read through Assimp, with the scene graph's nodes as objects.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <istream>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "viewcells/scene/scene.h"

namespace viewcells {

/// Loads a scene by extension (.obj, .ply, .off, .stl, .bsp, and through Assimp .gltf, .glb,
/// .fbx, .dae, .3ds, .x, .ase, .lwo, .ms3d). Throws Error naming the file (and the line for
/// OBJ) when it is missing, malformed, empty or has NaN/infinite coordinates. The groupings
/// kNodes and kMeshes apply to the Assimp formats only (for them kAuto and kGroups mean kNodes).
Scene load_scene(const std::string& path, ObjectGrouping grouping = ObjectGrouping::kAuto);

/// A scene format the readers below do not know, brought by a front end (the command line, the
/// Python module, a test): a Quake 3 map's reader lives with the rest of the map's code
/// (q3/bsp_file.h: register_q3_map_format()). load_scene reads a file whose extension
/// (lowercase, with the dot) is registered with `read`.
struct SceneFormat {
  std::string extension;  ///< ".bsp"
  std::string name;       ///< for messages: "Quake 3 map"
  std::function<RawMesh(const std::string& path)> read;
};
/// Registers `format` (again: replaces the one of the same extension). Thread-safe.
void register_scene_format(SceneFormat format);
/// The registered format of `path`'s extension (a copy), or none.
std::optional<SceneFormat> registered_scene_format(const std::string& path);

/// The extension of `path` in lower case, with its dot ("" when it has none).
inline std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// What becomes an object of a scene read through Assimp.
enum class AssimpObjects {
  kNodes,   ///< each node instance of the scene graph with meshes (its see-through meshes apart)
  kMeshes,  ///< each mesh of each node instance
};
/// True for the extensions (lower case, with the dot) that load_scene reads through Assimp.
bool is_assimp_extension(const std::string& ext);
/// Reads a scene through Assimp: transforms applied (in double), the file's up axis turned to
/// z, an instanced mesh once per node that references it, node names kept (made unique), groups
/// not occluding (RawMesh::group_occluder) where the material is alpha-blended, alpha-tested,
/// transmissive or not fully opaque. Points and lines are dropped.
RawMesh read_assimp(const std::string& path, AssimpObjects mode);
/// The same from bytes in memory; `extension` tells the format (".glb"). External buffers
/// (a .gltf's .bin) cannot be resolved this way.
RawMesh read_assimp_bytes(std::string_view bytes, const std::string& extension, AssimpObjects mode,
                          const std::string& name);

/// Largest coordinate magnitude a scene may hold: Embree's rays stop working beyond about 1.8e18.
inline constexpr double kMaxCoordinate = 1e18;

/// Returns the text of the material library `file` named by an OBJ's `mtllib` (relative to the
/// OBJ), or throws Error.
using MaterialLibraryReader = std::function<std::string(const std::string& file)>;
/// Parses OBJ text; `name` is used in error messages. Polygons are fan-triangulated. With
/// `read_mtl`, the `mtllib` files are read and faces whose `usemtl` material is see-through
/// (MTL dissolve `d` below 1, transparency `Tr` above 0, or a glass/refraction `illum` 4, 6, 7
/// or 9) form the group "NAME (see-through)", which does not occlude (RawMesh::group_occluder);
/// without it, materials are ignored.
RawMesh read_obj(std::istream& in, const std::string& name, const MaterialLibraryReader& read_mtl = {});
/// The names of the see-through materials (as read_obj decides) in MTL text.
std::vector<std::string> see_through_materials(std::string_view mtl, const std::string& name);
/// Parses the bytes of a PLY, OFF or STL file; `name` is used in error messages.
RawMesh read_ply(std::string_view bytes, const std::string& name);
RawMesh read_off(std::string_view bytes, const std::string& name);
RawMesh read_stl(std::string_view bytes, const std::string& name);

/// Writes the scene as OBJ with one `o` group per object (vertices shared within the file).
/// Writes to a temporary file and renames, so an existing file is never left half-written.
void write_obj(const Scene& scene, const std::string& path);

}  // namespace viewcells
