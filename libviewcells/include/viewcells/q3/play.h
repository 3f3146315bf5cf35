#pragma once
/// Where players stand and look on a Quake 3 map: cameras that represent play, for measuring
/// shipped PVSs (ours and the map's own) frame by frame. A camera stands at a player's eye
/// height above a floor a player can walk on, in non-solid space reachable from the map's
/// spawn points, looking as a player does (any yaw, pitch within a bound, no roll).
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/eval/frames.h"
#include "viewcells/viewspace/view_space.h"
#include "viewcells/q3/bsp_file.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/scene.h"
#include "viewcells/viewspace/floor_space.h"

namespace viewcells {

/// PlayCameraConfig (viewspace/view_space.h) holds the player's body: Quake 3's by default.

struct PlayCameras {
  std::vector<Camera> cameras;
  std::vector<int32_t> leaves;  ///< the map leaf of each camera's eye
  uint64_t points_drawn = 0;    ///< random points tried for the cameras
  size_t spawn_points = 0;
  size_t open_leaves = 0, reachable_leaves = 0;  ///< non-solid leaves; those reachable from a spawn
  std::string rule;  ///< how the cameras were placed, in words
};

/// The leaves with a cluster reachable from the map's spawn points through non-solid leaves
/// that share a face of positive area (every non-solid leaf when the map has no spawn point):
/// per map leaf, whether reachable.
std::vector<bool> q3_reachable_leaves(const Q3Map& map, size_t* spawn_points = nullptr);

/// Where a player's eye can be, as map leaves: the leaves reachable from the spawn points
/// (q3_reachable_leaves) that hold a point at most `reach` units above a walkable floor with
/// the space up to it free. Found by columns: `columns` uniform points of the walkable surfaces
/// (as the cameras draw them), each marking the leaves it passes every `step` units up to
/// `reach` or the first surface above. Quake 3's eye is 50 units above the floor and a jump
/// lifts it about 46 more (JUMP_VELOCITY 270, gravity 800), so the default reach of 112 takes
/// in a jumping player's eye with a margin; jump pads, falls and swimming are not play here.
struct PlaySpaceConfig {
  uint32_t columns = 1000000;
  uint64_t seed = 1;
  double reach = 112;
  double step = 8;
  double walk_normal = 0.7;
};

struct PlaySpace {
  std::vector<bool> leaves;       ///< per map leaf: a player's eye can be there
  size_t play_leaves = 0, open_leaves = 0;
  double play_volume = 0, open_volume = 0;  ///< of those leaves, and of all non-solid leaves
  std::string rule;               ///< in words
};

/// The play space of `map` (deterministic for a seed, for any number of threads). `caster`
/// casts against the scene made from the map. Error when the map has no walkable surface.
PlaySpace q3_play_space(const Q3Map& map, const Scene& scene, const RayCaster& caster, const PlaySpaceConfig& config);

/// `config.count` play cameras, drawn serially from `config.seed` (reproducible): a uniform
/// point of the walkable surfaces (rendered, occluding triangles whose normal points up at
/// least walk_normal; drawn by area), kept when player_height above it is free and the eye,
/// eye_height above it, lies in a reachable non-solid leaf. `caster` casts against the scene
/// made from the map (brush hulls included). Error when the map has too few such floors.
PlayCameras q3_play_cameras(const Q3Map& map, const Scene& scene, const RayCaster& caster,
                            const PlayCameraConfig& config);

/// How a play space found from meshes (find_floor_space on the map converted to glTF, scaled by
/// `found_scale` map units to its units) matches the map's own, over one eye band: the band of
/// `found` (its eye_low to eye_high above a walkable floor, taken from the map's scene). A point
/// is in the map's play space when its leaf is a play leaf (`play`, q3_play_space), it lies in
/// non-solid space, and the first surface below it is a walkable floor in the band; in the
/// found one when found.contains() says so. Volumes by `points` uniform points of the union of
/// both boxes (serially from `seed`), so each has a standard error of about
/// sqrt(volume * box / points). With `image_width`, also a top-down picture: per pixel column,
/// the floors of the map's scene below it, each tested at the middle of the band: green where
/// both hold it, red where only the map's does (missed), blue where only the found one does
/// (added), light grey where neither, white without floors.
struct PlaySpaceOverlap {
  double map_volume = 0, found_volume = 0, both_volume = 0;  ///< in map units^3
  double box_volume = 0;
  uint64_t points = 0;
  double coverage() const { return map_volume > 0 ? both_volume / map_volume : 0; }
  double excess() const { return map_volume > 0 ? (found_volume - both_volume) / map_volume : 0; }
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  ///< the picture, rows from +y down
};
PlaySpaceOverlap q3_play_space_overlap(const Q3Map& map, const Scene& scene, const RayCaster& caster,
                                       const PlaySpace& play, const FloorSpace& found, double found_scale,
                                       uint64_t points, uint64_t seed, int image_width = 0);

}  // namespace viewcells
