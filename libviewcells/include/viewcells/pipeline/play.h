#pragma once
/// `viewcells play-space`: the play space found from a scene's floors (viewspace/floor_space.h),
/// to look at (a top-down picture) and, for a level converted from a Quake 3 map, to check
/// against the map's own play space (level/level.h: LevelData::compare_play_space).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/pipeline/sampling.h"
#include "viewcells/viewspace/floor_space.h"

namespace viewcells {
struct GroupedMesh;  // vis/level_view.h (not installed): callers of floor_mesh and add_play_space include it
struct LevelView;
}  // namespace viewcells

namespace viewcells::pipeline {

struct PlaySpaceRunConfig {
  SceneSource scene;  ///< with the body, units and start points in scene.floors
  /// A Quake 3 map the scene was converted from (`viewcells convert`): its play space is the
  /// reference. Empty: none.
  std::string map;
  uint64_t points = 2'000'000;  ///< uniform points that measure the two volumes
  uint64_t seed = 1;
  std::string image;            ///< with `map`: a top-down PNG of where the two agree
  int image_width = 768;
  std::vector<Vec3> probes;     ///< points (scene units) to ask whether a player's eye can be there
};

struct PlaySpaceRun {
  PlaySpaceRunConfig config;
  std::string rule;  ///< what was found, in words
  bool found = false;
  double metres_per_unit = 1;
  double volume_m3 = 0, floor_area_m2 = 0;
  size_t spans = 0, reached_spans = 0;
  Box3 box;  ///< in the scene's units
  std::vector<bool> probes_in;  ///< per probe: in the play space
  double seconds = 0;
  /// Against the map: volumes in m^3 of the eye band in the map's play space, in the one found,
  /// in both; the map's play leaves' rule.
  struct Overlap {
    double map_m3 = 0, found_m3 = 0, both_m3 = 0, coverage = 0, excess = 0;
    uint64_t points = 0;
    std::string map_rule;
    double seconds = 0;
  };
  std::optional<Overlap> overlap;
};

PlaySpaceRun play_space(const PlaySpaceRunConfig& config, const Log& log);

/// A play space found from a scene's floors (as bake finds it), with the scene and ray caster
/// it refers to kept alive. A Quake 3 map gets none here: its play space is its BSP's leaves
/// (its level's view space); `space` is then null and `why` says so, as when no floor is found.
struct FoundPlaySpace {
  LoadedScene loaded;
  std::shared_ptr<const FloorSpace> space;  ///< null when none was found
  std::string why;                          ///< the rule found, or why there is none
};
FoundPlaySpace find_play_space(const SceneSource& source, const Log& log);

/// The reached floors for people to look at: FloorSpace::floor_rects() as one group of
/// triangles, lifted `lift_m` metres above the floors (so that they show over them).
GroupedMesh floor_mesh(const FloorSpace& space, double lift_m = 0.03);

/// The play space of `scene_path`'s floors (floor_mesh) added to a view of its cells, for the
/// web page and glTF (`viewcells view`); nothing, with the reason in view.play_space_rule, on a
/// level file (a registered level format: a Quake 3 map brings its own view space) or a scene
/// without floors.
void add_play_space(LevelView& view, const SceneSource& source, const Log& log);
/// The run's JSON report (indented, with a final newline).
std::string report_json(const PlaySpaceRun& run);

}  // namespace viewcells::pipeline
