#pragma once
/// Quake 3 BSP files (IBSP version 46, and 47 as Quake Live writes it): the world model's
/// surfaces (planar faces, triangle soups, Bezier patches), their shaders' flags, the
/// entities, and the BSP the map compiler built with its leaves, clusters and visibility
/// rows (q3map2's cluster PVS, the peer result). Every count, offset and index is checked:
/// a truncated or inconsistent file is an Error naming the file and the lump.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "viewcells/core/vec3.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

// Shader flags (q3map2's surfaceflags.h).
inline constexpr int32_t kQ3SurfSky = 0x4, kQ3SurfNodraw = 0x80, kQ3SurfHint = 0x100, kQ3SurfSkip = 0x200;
inline constexpr int32_t kQ3ContentsSolid = 0x1, kQ3ContentsLava = 0x8, kQ3ContentsSlime = 0x10,
                         kQ3ContentsWater = 0x20, kQ3ContentsFog = 0x40, kQ3ContentsTranslucent = 0x20000000;

struct Q3Shader {
  std::string name;
  int32_t surface_flags = 0, content_flags = 0;
};
struct Q3Plane {
  Vec3 normal;
  double dist = 0;
};
struct Q3Node {
  int32_t plane = 0;
  int32_t children[2] = {0, 0};  ///< >= 0: node; < 0: leaf -(child + 1)
};
struct Q3Leaf {
  int32_t cluster = -1;  ///< -1: solid (outside the map)
  int32_t area = 0;
  Box3 bounds;
  int32_t first_surface = 0, surface_count = 0;  ///< into leaf_surfaces
  int32_t first_brush = 0, brush_count = 0;      ///< into leaf_brushes
};
/// A convex brush of the map source: the intersection of its sides' back half-spaces.
struct Q3Brush {
  int32_t first_side = 0, side_count = 0;  ///< into brush_sides
  int32_t shader = 0;                      ///< content flags of the brush
};
struct Q3BrushSide {
  int32_t plane = 0;   ///< the side's plane; the brush lies behind it
  int32_t shader = 0;  ///< what the side's face would be drawn with
};
enum class Q3SurfaceType : int32_t { kBad = 0, kPlanar = 1, kPatch = 2, kTriangleSoup = 3, kFlare = 4 };
struct Q3Surface {
  int32_t shader = 0;
  Q3SurfaceType type = Q3SurfaceType::kBad;
  int32_t first_vertex = 0, vertex_count = 0, first_index = 0, index_count = 0;
  int32_t patch_width = 0, patch_height = 0;
};

/// How a surface takes part in visibility, from its shader.
enum class Q3SurfaceKind {
  kOpaque,        ///< occludes and is rendered: an object of the scene
  kSky,           ///< closes the map for rays; not rendered as an object
  kNonOccluding,  ///< water, fog, slime, lava, translucent: rendered, but rays pass through
  kSkipped,       ///< nodraw, hint, skip, flares, empty: not geometry at all
};

struct Q3Map {
  std::string path;
  int32_t version = 0;
  std::string entities;
  std::vector<Q3Shader> shaders;
  std::vector<Q3Plane> planes;
  std::vector<Q3Node> nodes;
  std::vector<Q3Leaf> leaves;
  std::vector<int32_t> leaf_surfaces;
  std::vector<Q3Brush> brushes;
  std::vector<Q3BrushSide> brush_sides;
  std::vector<int32_t> leaf_brushes;
  std::vector<Vec3> vertices;  ///< drawVerts positions
  std::vector<int32_t> indices;
  std::vector<Q3Surface> surfaces;
  int32_t world_first_surface = 0, world_surface_count = 0;  ///< model 0
  int32_t world_first_brush = 0, world_brush_count = 0;      ///< model 0
  int32_t cluster_count = 0, cluster_bytes = 0;  ///< 0 clusters: no visibility data
  std::vector<uint8_t> visibility;               ///< cluster_count rows of cluster_bytes

  bool has_visibility() const { return cluster_count > 0; }
  /// q3map2's PVS: whether cluster b is potentially visible from cluster a.
  bool cluster_sees(int32_t a, int32_t b) const;
  Q3SurfaceKind kind(const Q3Surface& s) const;
  /// The leaf containing p (walking the nodes).
  int32_t leaf_at(const Vec3& p) const;
  /// out[k] = leaf_at(base + (0, 0, heights[k])) for each k: the same leaves, found by one walk
  /// of the nodes for the whole vertical column. Error unless the heights ascend.
  void column_leaves(const Vec3& base, std::span<const double> heights, std::vector<int32_t>& out) const;
  /// Whether p lies in brush b: behind all of its sides, up to `slack` map units.
  bool in_brush(const Q3Brush& b, const Vec3& p, double slack = 1e-3) const;
  /// Whether brush b is solid matter that stops the eye (solid and not translucent contents).
  bool opaque_brush(const Q3Brush& b) const;
};

/// Parses a BSP file's bytes (`name` labels errors).
Q3Map parse_q3bsp(const std::string& bytes, const std::string& name);
/// Reads and parses a .bsp file.
Q3Map read_q3bsp(const std::string& path);

struct Q3MeshStats {
  size_t surfaces[4] = {0, 0, 0, 0};  ///< world surfaces by Q3SurfaceKind
  size_t patches = 0;                  ///< patch surfaces tessellated
  size_t spawn_points = 0;             ///< info_player_deathmatch / _start entities
  size_t brush_hulls = 0;              ///< solid brushes added as hulls
};

struct Q3MeshOptions {
  int patch_level = 4;  ///< segments per side of each Bezier piece of a patch
  /// Sky surfaces close the map for rays; their groups are marked not rendered (no cost).
  bool sky = true;
  /// Water, fog, slime, lava and translucent surfaces as objects that are rendered and seen
  /// through (they do not stop rays).
  bool see_through = true;
  /// The world's solid, non-translucent brushes as closed hulls set `hull_inset` inside their
  /// sides, in one group that occludes but is not rendered. The eye stops at solid matter even
  /// where no surface is drawn: caulk or clip sides (faces players never see from where they
  /// can stand) and cracks between triangles. Without hulls, rays cross such brushes.
  bool brush_hulls = true;
  double hull_inset = 0.5;  ///< map units: drawn faces lie on the sides and are hit first
};

/// The world model's geometry as a RawMesh with one group per surface, named
/// "shader#surface" (opaque surfaces and, per the options, the sky and the see-through
/// surfaces), plus the group
/// "solid brushes" of the brush hulls.
RawMesh q3_world_mesh(const Q3Map& map, const Q3MeshOptions& options = {}, Q3MeshStats* stats = nullptr);

/// Registers Quake 3 maps: the .bsp reader with load_scene (io/scene_io.h: the world's opaque
/// surfaces, the sky and the solid brushes that close it, neither rendered; patches at level 4;
/// one unit 1/32 m, a 56-unit player 1.75 m tall), and the map as a level (level/level.h,
/// q3/level.h). Front ends call it once; again changes nothing. Defined in q3/level.cpp.
void register_q3_map_format();

/// The worldspawn's "_farplanedist" (q3map2 leaves clusters beyond it out of the PVS; the
/// engine fogs them out), or 0 when the map has none.
double q3_far_plane(const Q3Map& map);

/// Spawn points: origins of info_player_deathmatch, info_player_start and the team spawns of
/// capture-the-flag maps (team_CTF_red/blueplayer, team_CTF_red/bluespawn).
std::vector<Vec3> q3_spawn_points(const Q3Map& map);

}  // namespace viewcells
