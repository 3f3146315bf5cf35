#pragma once
/// Where players stand on any triangle scene: walkable floors found by casting columns of rays
/// down through the scene, a player's eye band above them, reachable by walking, stepping and
/// dropping from start points. The play space of a level that brings no map compiler's BSP (a
/// glTF level from an editor), as a ViewSpace: cells are weighed, AGVS's points drawn and
/// measuring cameras placed where players are, as on a Quake 3 map.
///
/// The scene is z-up (every reader turns the file's up axis to z). Distances are in metres and
/// turned into the scene's unit by `metres_per_unit` (a glTF scene is in metres; a Quake 3 map's
/// unit is taken as 1/32 m, so that its 56-unit player is 1.75 m tall).
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/scene.h"
#include "viewcells/viewspace/view_space.h"

namespace viewcells {

/// The walkable surfaces, by area: rendered occluders whose normal points up by at least
/// `walk_normal` (the z of the unit normal). Draws uniform points of them.
class WalkableFloors {
 public:
  WalkableFloors(const Scene& scene, double walk_normal);
  bool empty() const { return floors_.empty(); }
  double area() const { return total_; }
  /// The point of the floors for three uniform numbers in [0, 1): uniform by area.
  Vec3 point(const Scene& scene, double pick, double u, double v) const;

 private:
  std::vector<std::pair<double, uint32_t>> floors_;  ///< (area so far, triangle)
  double total_ = 0;
};

/// Whether a name marks a sky ("sky" or "skies" in it, any case: a level's sky, a skybox, a
/// Quake 3 map's textures/skies/... surfaces): a sky is never a floor (below a level it is a
/// death pit).
bool sky_name(const std::string& name);

/// Whether a ray going down met a floor a player can stand on: the front of a rendered surface
/// whose normal points up by at least walk_normal (the back, for a closed object wound inside
/// out) and whose object is not a sky (sky_name). The back of an open surface is never a floor:
/// the top of a ceiling or of a sky seen from above is the inside of the level's shell.
bool walkable_floor_hit(const Scene& scene, const Hit& hit, double walk_normal);

/// A player's body and moves, in metres (see metres_per_unit). The defaults were chosen on the
/// tuning half of the maps (docs/play-space.md).
struct FloorSpaceConfig {
  /// Metres in one unit of the scene; 0: the scene's own (Scene::metres_per_unit), or 1 when
  /// the scene does not say (OBJ, PLY, arrays), which the rule then says.
  double metres_per_unit = 0;
  double cell = 0.25;           ///< spacing of the columns of rays, m
  double walk_normal = 0.7;     ///< least z of a walkable floor's unit normal (45.6 degrees)
  double player_height = 1.75;  ///< free space a standing player needs above the floor, m
  double step = 0.6;            ///< the highest step a player walks up, m (stairs, kerbs)
  double eye_low = 1.0;         ///< the eye band above a floor: from a crouch, m
  double eye_high = 3.0;        ///< to the top of a jump, m
  /// A floor region (spans joined by walking both ways) of at least this area is a start, m^2
  /// (see start_points).
  double min_region = 4;
  uint32_t max_columns = 4'000'000;  ///< more: the cell grows until the grid fits
  /// Where players start, in scene units (spawn points); empty: the scene's own
  /// (Scene::start_points). What they reach is in the play space, and so is every floor region
  /// of at least min_region within region_margin (horizontally) of what they reach: walking
  /// from spawn points misses what jump pads and teleporters reach, and a bake that leaves out
  /// where players stand draws far more there, while a level's backdrop around its playable
  /// part stays out. With only_from_starts, only what they reach. With no start points, every
  /// region of at least min_region.
  std::vector<Vec3> start_points;
  bool only_from_starts = false;
  double region_margin = 10;  ///< m
};

/// The play space found (find_floor_space): columns of floor spans on a grid over the scene.
class FloorSpace {
 public:
  /// A place a player stands in one column: the floor's height, the first surface above it.
  struct Span {
    double floor = 0, ceiling = 0;
  };

  /// Whether a player's eye can be at p: p is not above the scene's bounds, the first surface
  /// straight below p is a walkable floor between eye_low and eye_high below it, and a reached
  /// span of that floor's column or of one next to it lies within a step of it. Casts one ray
  /// (thread-safe).
  bool contains(const Vec3& p) const;
  /// A point of the eye band over the reached spans for three uniform numbers in [0, 1) (uniform
  /// by band volume over the columns); a NaN x when it is not in contains() (near walls).
  Vec3 point(double u0, double u1, double u2) const;
  /// `count` points uniform in contains(), drawn from `seed` (any number of threads: the same).
  std::vector<Vec3> uniform_points(uint32_t count, uint64_t seed) const;

  bool empty() const { return band_volume_ <= 0; }
  /// Box of the reached spans' eye bands.
  const Box3& box() const { return box_; }
  /// The reached spans' eye band's volume, and the floor area under it (spans with room for an
  /// eye: not a roof at the scene's top), in scene units.
  double volume() const { return band_volume_; }
  double floor_area() const { return reached_area_; }
  size_t spans() const { return spans_.size(); }
  size_t reached_spans() const { return reached_count_; }
  /// The reached floors for people to look at: rectangles of columns in a row whose reached
  /// spans stand at the same height (within 1 mm) and have an eye band (not a roof at the
  /// scene's top), scene units.
  struct FloorRect {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0, z = 0;
  };
  std::vector<FloorRect> floor_rects() const;
  /// What was found and how, in words (for logs and reports).
  const std::string& rule() const { return rule_; }
  /// The body in scene units.
  const FloorSpaceConfig& units() const { return u_; }
  double metres_per_unit() const { return mpu_; }

 private:
  friend FloorSpace find_floor_space(const Scene& scene, const RayCaster& caster, const FloorSpaceConfig& config);
  int64_t column_of(double x, double y) const;
  double band_of(const Span& s) const;

  const Scene* scene_ = nullptr;
  const RayCaster* caster_ = nullptr;
  FloorSpaceConfig u_;  ///< distances in scene units
  double mpu_ = 1;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  double top_ = 0;  ///< the scene's top: no eye above it
  int64_t nx_ = 0, ny_ = 0;
  std::vector<uint32_t> first_;  ///< per column, its first span; one past the last at the end
  std::vector<Span> spans_;
  std::vector<uint8_t> reached_;
  std::vector<std::pair<double, uint32_t>> by_band_;  ///< (band volume so far, span), reached spans
  size_t reached_count_ = 0;
  double band_volume_ = 0, reached_area_ = 0;
  Box3 box_;
  std::string rule_;
};

/// Finds the play space of `scene` (deterministic, for any number of threads). `caster` casts
/// against `scene`; both must outlive the result. Empty (FloorSpace::empty(), the rule saying
/// why) when the scene has no walkable floor with room for a player, or none reached.
FloorSpace find_floor_space(const Scene& scene, const RayCaster& caster, const FloorSpaceConfig& config);

/// The play space as a ViewSpace: segments sampled in its box (taller by nothing: the eye band's),
/// the subdivision's viewpoints and AGVS's points uniform in it, cameras at a standing player's
/// eye above its floors.
std::shared_ptr<const ViewSpace> floor_view_space(std::shared_ptr<const FloorSpace> space);

/// The view space of a scene that brings no view space of its own: the whole view box
/// (box_view_space()), whose play space (ViewSpace::play_space) is found from its floors with
/// `config` the first time it is asked (null when it has none).
std::shared_ptr<const ViewSpace> mesh_view_space(FloorSpaceConfig config = {});

}  // namespace viewcells
