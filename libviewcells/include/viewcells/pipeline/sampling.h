#pragma once
/// The pipeline's first stages, shared by every command that casts rays: load a scene file
/// (a Quake 3 map brings its non-solid view space), build its ray caster, sample visibility
/// segments. Each pipeline function takes a Config and returns a typed result; its report
/// is written by pipeline/report.h. `Log` receives one line per step for a human.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "viewcells/agvs/agvs.h"
#include "viewcells/hidden/hidden_space.h"
#include "viewcells/viewspace/floor_space.h"
#include "viewcells/viewspace/view_space.h"
#include "viewcells/level/level.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/scene.h"

namespace viewcells::pipeline {

using Log = std::function<void(const std::string&)>;

/// A scene file and how to read it.
struct SceneSource {
  std::string path;  ///< the scene file; with `scene`, only a name for logs and reports
  ObjectGrouping grouping = ObjectGrouping::kAuto;
  bool robust = true;  ///< Embree's robust mode (off: faster, rays may slip through edges)
  /// A scene made in memory (an editor's meshes, Python's arrays): used instead of reading
  /// `path`, with its own objects (`grouping` does not apply). Shared, never modified.
  std::shared_ptr<const Scene> scene;
  /// How a scene without a view space of its own finds where players stand (units, the
  /// player's body, start points): viewspace/floor_space.h.
  FloorSpaceConfig floors;
};

/// The view space a scene brings (viewspace/view_space.h): its level's (`level` not null and
/// knowing one, as a Quake 3 map does), else the whole view box with a play space found from the
/// scene's floors when asked (viewspace/floor_space.h). The one place that picks a view space.
std::shared_ptr<const ViewSpace> view_space_of(const std::shared_ptr<const LevelData>& level,
                                              const FloorSpaceConfig& floors = {});

/// A scene ready for rays. The scene is held by pointer: the caster refers to it, so it must
/// not move when the LoadedScene does.
struct LoadedScene {
  SceneSource source;
  std::unique_ptr<const Scene> scene;
  std::unique_ptr<RayCaster> caster;
  /// What the scene file brings besides its triangles (level/level.h: a Quake 3 map's BSP and
  /// PVS), when its format is a registered level format; null otherwise.
  std::shared_ptr<const LevelData> level;
  /// Where viewpoints can be (view_space_of): the pipeline asks it, never the kind of scene. It
  /// keeps its play space once found, so that the division, merging and AGVS of one bake share it.
  std::shared_ptr<const ViewSpace> view_space = box_view_space();
  double load_seconds = 0, bvh_seconds = 0;
};

/// What the scene can prove hidden (hidden/hidden_space.h): its level's (a Quake 3 map's BSP), else the
/// scene's closed convex solids; null, with the reason in `why`, when it can prove nothing.
std::shared_ptr<const HiddenSpace> hidden_space_of(const LoadedScene& loaded, std::string& why);

/// Loads the scene and builds its ray caster.
LoadedScene load_scene_for_rays(const SceneSource& source, const Log& log);

/// The part of the scene's view space where players stand (ViewSpace::play_space: on a Quake 3
/// map, the leaves a player's eye can reach), found once. Error when the view space knows no
/// players.
std::shared_ptr<const ViewSpace> play_view_space(const LoadedScene& loaded);

/// Loading and sampling, with what a report needs.
struct SamplingRun {
  LoadedScene loaded;
  SamplerConfig config;
  SamplingResult result;
  int threads = 1;
  bool view_box_given = false;  ///< the caller set config.view_box
};

/// Loads the scene and samples it (the map's view space on a Quake 3 map).
SamplingRun load_and_sample(const SceneSource& source, const SamplerConfig& config, const Log& log);
/// The same for a scene already loaded (it moves into the result).
SamplingRun sample_loaded(LoadedScene loaded, const SamplerConfig& config, const Log& log);

/// `viewcells sample`: segments, optionally written as .vseg, and optionally Embree's raw
/// speed on the same rays.
struct SampleConfig {
  SceneSource scene;
  SamplerConfig sampling;
  std::string segments_path;  ///< empty: not written
  bool measure_raw = false;
};

struct RawRayTiming {
  uint64_t rays = 0;
  double seconds = 0;
};

struct SampleResult {
  SamplingRun run;
  double write_seconds = 0;
  std::optional<RawRayTiming> raw;
};

SampleResult sample(const SampleConfig& config, const Log& log);

}  // namespace viewcells::pipeline
