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
#include "viewcells/io/q3bsp.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/scene.h"

namespace viewcells {
struct PlaySpace;
}

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
};

/// True for a Quake 3 map (.bsp).
bool is_q3_map(const std::string& path);

/// A scene ready for rays. The scene is held by pointer: the caster refers to it, so it must
/// not move when the LoadedScene does.
struct LoadedScene {
  SceneSource source;
  std::unique_ptr<const Scene> scene;
  std::unique_ptr<RayCaster> caster;
  std::shared_ptr<const Q3Map> map;  ///< the Quake 3 map, when the scene is one
  /// The map's play space (q3_play_space with its defaults), once play_space() has found it:
  /// the division, merging and AGVS of one bake share it.
  std::shared_ptr<const PlaySpace> play;
  double load_seconds = 0, bvh_seconds = 0;
  std::string view_space = "the whole view box";  ///< where sample origins are drawn, in words
};

/// Loads the scene and builds its ray caster.
LoadedScene load_scene_for_rays(const SceneSource& source, const Log& log);

/// A Quake 3 map's view space is its non-solid space: sample origins are drawn there, and the
/// view box defaults to the bounds of its non-solid leaves. Nothing for other scenes.
void use_map_view_space(LoadedScene& loaded, SamplerConfig& config);

/// On a Quake 3 map (`map` not null), AGVS draws its points in the map's non-solid space too.
void use_map_view_space(const std::shared_ptr<const Q3Map>& map, AgvsConfig& config);
/// The view box a written .pvs gives its cells: `box`, and on a Quake 3 map (`map` not null)
/// every point of its non-solid space (q3_cover_box), so that an engine finds a cell wherever
/// a player can stand. The BSP's cells at the rim reach out to it; nothing else changes.
Box3 covered_view_box(const Q3Map* map, const Box3& box);
/// The play space of a Quake 3 map (q3_play_space with its defaults), found the first time
/// and kept in `loaded.play`. Error for other scenes.
const PlaySpace& play_space(LoadedScene& loaded);

/// On a Quake 3 map, AGVS draws its points in the play space's leaves (play_space()), so that
/// its pixel error estimate is that of cameras where players are (with --play-space).
void use_play_view_space(LoadedScene& loaded, AgvsConfig& config);

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
