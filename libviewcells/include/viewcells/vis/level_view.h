#pragma once
/// View cells and their PVSs for people to look at outside this toolkit: as a glTF 2.0 file
/// (Blender, engines) and as a static web page (three.js) that shows the scene, the cells
/// coloured by render cost or PVS size, and a chosen cell's PVS highlighted.
#include <string>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// Triangles in float, grouped in consecutive ranges (one range per object or per cell).
struct GroupedMesh {
  std::vector<float> positions;        ///< xyz per vertex
  std::vector<uint32_t> indices;       ///< three per triangle
  std::vector<uint32_t> first_vertex;  ///< per group, and one past the last
  std::vector<uint32_t> first_index;   ///< per group, and one past the last
  size_t group_count() const { return first_vertex.empty() ? 0 : first_vertex.size() - 1; }
};

/// What both views show: the view cells of a .pvs file (the union of their BSP leaves, each
/// leaf shrunk a little towards its centre so neighbours stay apart), their PVSs and render
/// costs, and the scene they belong to.
struct LevelView {
  GroupedMesh cells;                         ///< one group per view cell
  GroupedMesh scene;                         ///< one group per object
  std::vector<std::vector<uint32_t>> pvs;    ///< per view cell, sorted object ids
  std::vector<double> cell_cost;             ///< per view cell: r(PVS)
  std::vector<double> object_cost;           ///< per object: its share of r(PVS)
  std::vector<uint32_t> object_triangles;    ///< per object
  std::vector<uint8_t> object_see_through;   ///< per object: does not stop rays (glass, water)
  std::vector<std::string> object_names;
  CostModel model;
  PvsFile file;                              ///< point location (BSP, leaf -> cell) and the rule
  std::string scene_source;
  /// Where players are assumed to stand (pipeline::add_play_space): the play space's floors, one
  /// group (empty: none drawn), and its rule or why there is none.
  GroupedMesh play_space;
  std::string play_space_rule;
};

/// Builds the views' content. Throws Error when `scene` is not the scene `f` was made for
/// (fingerprints differ). The cost model's pixel term is not used (c = 0): a cell's colour
/// is sum over its PVS of max(a, b * triangles).
LevelView make_level_view(PvsFile f, const Scene& scene, const CostModel& model);

/// Writes a binary glTF 2.0 (.glb): node "scene" with one child node per object (named, grey;
/// see-through objects translucent), node "view cells" with one child per view cell (colour
/// from blue to red by render cost, translucent), whose extras hold its id, render cost, PVS
/// size and PVS (object ids); the asset's extras hold the object names, the cost model and the
/// rule the cells were cut by; with a play space, node "play space" (its floors, green,
/// translucent; extras: the rule). Written atomically.
void write_level_gltf(const std::string& path, const LevelView& view);

/// How write_scene_gltf writes a scene.
struct SceneGltfOptions {
  /// Metres in one unit of the scene: vertices are scaled by it (glTF is in metres).
  double metres_per_unit = 1;
  /// Where players start, in scene units: written as empty nodes named "spawn N", as a level
  /// editor marks them (read back into Scene::start_points).
  std::vector<Vec3> start_points;
  /// Per object: written (empty: the rendered objects). A glTF level has no objects that stop
  /// rays unseen: what is written is rendered.
  std::vector<uint8_t> keep;
};
/// Writes `scene` as a binary glTF 2.0 (.glb) level, y-up in metres: one node per object kept,
/// in the scene's object order (named as the object; see-through objects translucent), and
/// nothing else of the source (no brushes, leaves or entities beyond the start points asked
/// for). Written atomically.
void write_scene_gltf(const std::string& path, const Scene& scene, const SceneGltfOptions& options);

/// Writes the static web viewer into directory `dir` (created when missing): index.html,
/// viewer.js (three.js and the viewer, bundled when viewcells was built) and data.js (the
/// level). It opens from the file system without a server. Throws Error when this build has
/// no viewer bundle (see require_web_viewer()).
void write_web_viewer(const std::string& dir, const LevelView& view);
/// Throws Error, saying what to do, when viewcells was built without the web viewer (no
/// web/node_modules at build time).
void require_web_viewer();

}  // namespace viewcells
