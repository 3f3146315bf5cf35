#pragma once
/// The scene: triangles in double precision, grouped into objects (the units a PVS lists).
/// Per object it knows triangle count, bounds, area and whether it is a closed, consistently
/// and outward oriented solid (the precondition of empty view space detection, paper 4.1).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/core/vec3.h"

namespace viewcells {

inline constexpr uint32_t kNoObject = 0xffffffffu;

/// How triangles become objects.
enum class ObjectGrouping {
  kAuto,        ///< OBJ `o`/`g` groups when the file has any, otherwise connected components
  kGroups,      ///< file groups (a file without groups gives a single object)
  kComponents,  ///< connected components (triangles sharing a vertex position)
  kTriangles,   ///< every triangle is an object
  kNodes,       ///< scene-graph formats (glTF, FBX): each node instance with meshes
  kMeshes,      ///< scene-graph formats: each mesh of each node instance
};

/// Parses "auto", "groups", "components", "triangles", "nodes", "meshes"; throws Error otherwise.
ObjectGrouping parse_grouping(const std::string& name);
const char* to_string(ObjectGrouping g);

struct ObjectInfo {
  std::string name;
  uint32_t triangle_count = 0;
  Box3 bounds;
  double surface_area = 0;
  bool closed = false;    ///< every edge is shared by exactly two of the object's triangles
  bool oriented = false;  ///< closed, and each edge is traversed once in each direction
  double signed_volume = 0;  ///< > 0 when normals point outwards (only meaningful if oriented)
  /// Drawn by the renderer, so it counts in r(PVS). False for geometry that only closes the
  /// scene for rays, such as a game level's sky (it occludes but costs nothing).
  bool rendered = true;
  /// Stops rays. False for surfaces one sees through (water, glass, fog): they are seen, and
  /// so in PVSs, wherever a segment crosses them, but hide nothing.
  bool occluder = true;
  /// Closed, consistently oriented, normals outwards: back-face hits mean "inside".
  bool solid() const { return closed && oriented && signed_volume > 0; }
};

/// Triangles as read, before grouping: the loaders' output.
struct RawMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<uint32_t> triangle_group;  ///< index into group_names, one per triangle
  std::vector<std::string> group_names;  ///< empty when the file has no groups
  /// Per group: false when the group is not rendered (ObjectInfo::rendered); empty: all are.
  std::vector<uint8_t> group_rendered;
  /// Per group: false when the group does not stop rays (ObjectInfo::occluder); empty: all do.
  std::vector<uint8_t> group_occluder;
  /// With ObjectGrouping::kGroups: object i is group i, for every group, also one left with no
  /// triangles (none given, or all degenerate: then neither rendered nor an occluder), so that
  /// the ids in every PVS are the caller's (arrays from Python, the C API). Otherwise objects
  /// are the groups with triangles, in order of first appearance.
  bool keep_group_ids = false;
  /// Metres in one unit, when the file says (glTF: 1); 0: unknown.
  double metres_per_unit = 0;
  /// Where players start (spawn points), when the file marks them (glTF nodes named so).
  std::vector<Vec3> start_points;
};

class Scene {
 public:
  std::vector<Vec3> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<uint32_t> triangle_object;  ///< object id of each triangle
  std::vector<ObjectInfo> objects;
  std::string source;                ///< file it came from, or generator description
  uint64_t degenerate_dropped = 0;   ///< zero-area triangles removed while loading
  ObjectGrouping grouping = ObjectGrouping::kAuto;
  /// Metres in one unit, when the file says (glTF: 1; a Quake 3 map: 1/32); 0: unknown. Not
  /// part of the fingerprint.
  double metres_per_unit = 0;
  /// Where players start (spawn points) when the file marks them: a glTF's nodes named
  /// "spawn", "player start" and the like (io/scene_io.h). Not part of the fingerprint.
  std::vector<Vec3> start_points;

  // Derived by finalize():
  Box3 bounds;
  double surface_area = 0;
  double non_axis_aligned_area = 0;  ///< area of triangles whose normal is not along an axis
  bool all_solid = false;            ///< every object is solid(): empty-space detection applies

  size_t triangle_count() const { return triangles.size(); }
  size_t object_count() const { return objects.size(); }
  /// Share of the surface area lying in planes not perpendicular to an axis, in [0, 1].
  double non_axis_aligned_share() const {
    return surface_area > 0 ? non_axis_aligned_area / surface_area : 0.0;
  }
  /// Triangle normal (v1-v0)x(v2-v0), not normalised; front side is where it points.
  Vec3 triangle_normal(uint32_t t) const {
    const auto& tri = triangles[t];
    return cross(vertices[tri[1]] - vertices[tri[0]], vertices[tri[2]] - vertices[tri[0]]);
  }
  /// Recomputes bounds, areas and per-object closedness. Call after editing geometry.
  void finalize();
  /// 64-bit fingerprint of the geometry and object assignment (stored in sample files).
  uint64_t fingerprint() const;
};

/// Builds a scene: drops degenerate triangles (counted), assigns objects, finalizes.
/// Throws Error (naming `source`) on non-finite vertices or out-of-range indices.
Scene make_scene(RawMesh mesh, ObjectGrouping grouping, const std::string& source);

/// Rotates every vertex about the vertical (z) axis through `pivot`, then finalizes.
void rotate_about_z(Scene& scene, double degrees, const Vec3& pivot);
/// Translates every vertex, then finalizes.
void translate(Scene& scene, const Vec3& offset);

}  // namespace viewcells
