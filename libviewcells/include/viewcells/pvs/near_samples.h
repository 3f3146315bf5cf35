#pragma once
/// Near-object samples: after AGVS, each view cell tests the objects that touch what it already
/// sees. Measured on Quake 3 maps, the holes players see are almost all objects whose boxes lie
/// within a few units of an object in the cell's PVS (trims, frames, steps beside visible walls
/// and floors, seen at grazing angles or through narrow gaps that random rays rarely pass):
/// adding every such neighbour closes them but doubles the PVSs (docs/accuracy-vs-time.md). So
/// each neighbour is tested instead: rays from the cell's viewpoints (player eyes on a map) to
/// random points on the neighbour's surface, and it joins the PVS only when one arrives
/// unblocked. What joins brings its own neighbours into the next round. This is the paper's
/// idea of sampling where the error is (AGVS section 4.3: mutations near what was found),
/// aimed at the objects the measurement shows missing, and it adds only visible objects, so
/// the render cost grows by what was really missed.
#include <cstdint>
#include <span>
#include <vector>

#include "viewcells/core/vec3.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

struct NearSampleConfig {
  uint32_t rays_per_object = 2048;  ///< rays from the cell to each neighbour tested, per round (0: none)
  uint32_t rounds = 4;              ///< rounds; a round tests the neighbours of what the last one added
  /// Objects are neighbours when their bounding boxes are at most this far apart; <= 0: 1e-3 of
  /// the scene's bounding box diagonal.
  double distance = 0;
  /// All rounds' rays at most (a bound on the time whatever the scene): where the candidates
  /// would take more, a round casts fewer rays a candidate, in packets of 16.
  uint64_t max_rays = uint64_t{1} << 31;
  /// Seconds at most (0: no limit): past them no further cell is started and no round begins
  /// (then, and only then, the lists depend on the machine's speed).
  double max_seconds = 0;
  uint64_t seed = 1;
};

struct NearSampleStats {
  uint64_t tested = 0;  ///< (cell, object) pairs tested, over all rounds
  uint64_t rays = 0;
  uint64_t added = 0;   ///< PVS entries added
  double distance = 0;  ///< the neighbour distance used
  std::vector<uint64_t> added_by_round;
  std::vector<uint64_t> rays_by_round;  ///< rays a candidate each round cast (below K under max_rays)
  bool stopped_by_time = false;         ///< max_seconds ran out
};

/// Pairs of rendered objects whose bounding boxes are within `distance` of each other, as a
/// sorted neighbour list per object (sweep along x over the boxes sorted by their low x).
std::vector<std::vector<uint32_t>> object_neighbours(const Scene& scene, double distance);

/// Tests, for every view cell with viewpoints, the neighbours of its PVS that it lacks (see
/// above) and adds those a ray reaches. `eyes[c]` are cell c's viewpoints (none: the cell is
/// left as it is); `lists[c]` its sorted PVS, extended in place. Parallel over cells with a
/// random stream per (seed, round, cell): the lists do not depend on the threads.
NearSampleStats add_near_samples(const Scene& scene, const RayCaster& caster,
                                 const std::vector<std::vector<Vec3>>& eyes, const NearSampleConfig& config,
                                 std::vector<std::vector<uint32_t>>& lists);

}  // namespace viewcells
