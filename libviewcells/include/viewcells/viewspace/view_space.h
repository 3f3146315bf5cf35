#pragma once
/// One home for view spaces: where viewpoints can be, how view cells are weighed, and where
/// cameras stand (the paper's view space and viewpoint density p(i), section 3.3). The
/// pipeline asks a ViewSpace and never which kind of scene it has: a scene's loader picks one
/// (box_view_space() below, or a Quake 3 map's non-solid space, q3/map_view_space.h), and
/// --play-space asks it for the part where players stand. A new kind of level (a navmesh, a
/// street band) is a new implementation of this interface: the loader's choice
/// (pipeline::view_space_of) names it, or a caller hands it in LoadedScene::view_space; nothing
/// else in the pipeline changes.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "viewcells/agvs/agvs.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/cells/view_cells.h"
#include "viewcells/eval/frames.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// Where measuring cameras stand: auto is the view space's own choice (players' eyes where it
/// knows players, else the view box); play needs a view space that knows players.
enum class CameraPlacement { kAuto, kPlay, kViewBox };

/// A player's body, for cameras where players stand. The defaults are Quake 3's player: a box
/// 56 units tall whose origin is 24 units above its feet, the eye 26 above the origin
/// (DEFAULT_VIEWHEIGHT); floors up to 45.6 degrees steep are walkable (MIN_WALK_NORMAL 0.7).
struct PlayCameraConfig {
  uint32_t count = 5000;
  uint64_t seed = 1;
  double eye_height = 50;      ///< above the floor
  double player_height = 56;   ///< free space needed above the floor
  double walk_normal = 0.7;    ///< least z of a walkable floor's unit normal
  double max_pitch_degrees = 30;  ///< pitch uniform in [-max, max], yaw uniform
};

struct CameraConfig {
  CameraPlacement placement = CameraPlacement::kAuto;
  uint32_t count = 5000;
  uint64_t seed = 1;
  PlayCameraConfig play;  ///< count and seed come from above
};

/// Cameras for measuring frames, and the view cell of each.
struct CameraSet {
  std::vector<Camera> cameras;
  std::vector<int32_t> cells;
  std::string rule;  ///< how they were placed, in words
  uint64_t points_drawn = 0;
};

class ViewSpace {
 public:
  virtual ~ViewSpace() = default;

  /// Where sample origins are drawn, in words (logs and reports).
  virtual std::string describe() const = 0;

  /// Restricts the segment sampler: its view box when the caller gave none, and where its
  /// origins may be (an origin outside is drawn again). Nothing for the whole view box.
  virtual void restrict(SamplerConfig& config) const { (void)config; }
  /// Where restrict() takes the view box from when the caller gives none, in words.
  virtual std::string box_rule() const { return "scene bounds"; }
  /// Restricts AGVS's points in the same way (and may say how they are drawn).
  virtual void restrict(AgvsConfig& config) const { (void)config; }

  /// The box a written file's cells cover, containing `box`: an engine must find a cell
  /// wherever a viewer can stand, even where the sampled box does not reach.
  virtual Box3 covered_box(const Box3& box) const { return box; }

  /// The subdivision's viewpoint density (SubdivisionConfig::viewpoints) for cells over `box`,
  /// drawn from config.seed; nothing when viewpoints are uniform in the view space.
  virtual void set_viewpoints(SubdivisionConfig& config, const Box3& box) const {
    (void)config;
    (void)box;
  }
  /// The viewpoint density set_viewpoints gives, in words; empty: uniform.
  virtual std::string viewpoint_rule() const { return {}; }

  /// Sets p(i) of every node of a subdivision over `box` to this view space's share of its
  /// cell (its leaves' cells must be present). Empty: the subdivision's own weights stand
  /// (volume, or its density band). The function holds what it needs, built once for `box`.
  virtual std::function<void(Subdivision&)> weigher(const Box3& box) const {
    (void)box;
    return {};
  }
  /// What weigher() weighs by, in words ("their volume in ...").
  virtual std::string weight_rule() const { return {}; }

  /// Cameras for measuring frames (drawn serially from config.seed: reproducible). `cell_at`
  /// gives a point's view cell (-1: none); `locator` holds the view cells. Error for a count of
  /// 0, or a placement this view space cannot give.
  CameraSet cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& config,
                    const std::function<int32_t(const Vec3&)>& cell_at, const CellLocator* locator) const;
  /// Error when cameras() cannot give `config` (a count of 0, play cameras where the view
  /// space knows no players): what a command checks before its work.
  void check_cameras(const CameraConfig& config) const;
  /// Whether cameras stand where players do with placement kPlay (and kAuto picks them).
  virtual bool knows_players() const { return false; }
  /// Whether play cameras may be asked for: knows_players(), or a view space that finds its
  /// players when asked (a mesh scene's floors; kAuto then keeps its own placement).
  virtual bool may_know_players() const { return knows_players(); }
  /// Why play_space() found none, in words, once it was asked; empty otherwise.
  virtual std::string no_play_space_reason() const { return {}; }

  /// The part of this view space where players stand, as a view space of its own; null when
  /// this one knows no players (or, for a mesh scene, finds no floor a player can reach). Found
  /// once (the same object for later calls).
  virtual std::shared_ptr<const ViewSpace> play_space(const Scene& scene, const RayCaster& caster) const {
    (void)scene;
    (void)caster;
    return nullptr;
  }

 protected:
  virtual CameraSet place_cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& config,
                                  const std::function<int32_t(const Vec3&)>& cell_at,
                                  const CellLocator* locator) const = 0;
};

/// The whole view box: viewpoints anywhere in it (outside closed objects, where the scene has
/// them), p(i) = V_i / V, cameras at random points of it looking anywhere.
std::shared_ptr<const ViewSpace> box_view_space();

}  // namespace viewcells
