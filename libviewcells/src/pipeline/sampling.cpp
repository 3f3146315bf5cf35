/// The pipeline's first stages: load a scene with the view space it brings, build its ray caster,
/// sample visibility segments (paper 4.1).
#include "viewcells/pipeline/sampling.h"


#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/viewspace/floor_space.h"

namespace viewcells::pipeline {

std::shared_ptr<const ViewSpace> view_space_of(const std::shared_ptr<const LevelData>& level,
                                              const FloorSpaceConfig& floors) {
  std::shared_ptr<const ViewSpace> own = level ? level->view_space() : nullptr;
  return own ? own : mesh_view_space(floors);
}

std::shared_ptr<const HiddenSpace> hidden_space_of(const LoadedScene& loaded, std::string& why) {
  why.clear();
  if (loaded.level) return loaded.level->hidden_space(*loaded.scene, why);
  return solid_objects_hidden_space(*loaded.scene, why);
}

LoadedScene load_scene_for_rays(const SceneSource& source, const Log& log) {
  LoadedScene out;
  out.source = source;
  Stopwatch sw;
  if (source.scene) {
    if (source.scene->triangles.empty()) throw Error(source.path, 0, "the scene has no triangles");
    out.scene = std::make_unique<const Scene>(*source.scene);
  } else {
    out.scene = std::make_unique<const Scene>(load_scene(source.path, source.grouping));
    out.level = read_level_data(source.path);
  }
  out.view_space = view_space_of(out.level, source.floors);
  out.load_seconds = sw.seconds();
  log("viewcells: " + source.path + ": " + std::to_string(out.scene->object_count()) + " objects, " +
      std::to_string(out.scene->triangle_count()) + " triangles, loaded in " + fmt(out.load_seconds, 2) + " s");
  sw.restart();
  EmbreeConfig ec;
  ec.robust = source.robust;
  out.caster = make_embree_caster(*out.scene, ec);
  out.bvh_seconds = sw.seconds();
  return out;
}

std::shared_ptr<const ViewSpace> play_view_space(const LoadedScene& loaded) {
  std::shared_ptr<const ViewSpace> play = loaded.view_space->play_space(*loaded.scene, *loaded.caster);
  if (!play) {
    const std::string why = loaded.view_space->no_play_space_reason();
    throw Error(loaded.source.path + ": --play-space needs a view space that knows where players stand: " +
                (why.empty() ? loaded.view_space->describe() + " has no spawn points and floors to find it from"
                             : "the scene has none: " + why));
  }
  return play;
}

SamplingRun load_and_sample(const SceneSource& source, const SamplerConfig& config, const Log& log) {
  if (config.samples == 0 && config.target_segments == 0) throw Error("--samples must be positive");
  return sample_loaded(load_scene_for_rays(source, log), config, log);
}

SamplingRun sample_loaded(LoadedScene loaded, const SamplerConfig& config, const Log& log) {
  if (config.samples == 0 && config.target_segments == 0) throw Error("--samples must be positive");
  SamplingRun out;
  out.config = config;
  out.view_box_given = !config.view_box.empty();
  out.threads = worker_threads();
  out.loaded = std::move(loaded);
  out.loaded.view_space->restrict(out.config);
  const SamplerConfig& c = out.config;
  const EmptySpaceDecision esd = decide_empty_space(*out.loaded.scene, c.empty_space);
  log("viewcells: sampling " +
      (c.target_segments ? "until " + std::to_string(c.target_segments) + " segments"
                         : std::to_string(c.samples) + " samples") +
      ", seed " + std::to_string(c.seed) + ", " + std::to_string(out.threads) + " threads, " +
      out.loaded.caster->name() + "; view box " + (c.view_box.empty() ? "= scene bounds" : describe_box(c.view_box)) +
      "; view space " + out.loaded.view_space->describe() + "; empty space detection " + esd.reason);
  out.result = sample_segments(*out.loaded.scene, *out.loaded.caster, c);
  const SamplingStats& st = out.result.stats;
  log("viewcells: " + std::to_string(st.valid_segments) + " valid segments of " + std::to_string(st.samples) +
      " samples (" + std::to_string(st.rays) + " rays) in " + fmt(st.seconds, 2) + " s: " +
      fmt(st.valid_segments / st.seconds / 1e6, 3) + " M segments/s");
  return out;
}

SampleResult sample(const SampleConfig& config, const Log& log) {
  SampleResult out;
  out.run = load_and_sample(config.scene, config.sampling, log);
  const SamplingRun& s = out.run;
  const SamplingStats& st = s.result.stats;
  Stopwatch sw;
  if (!config.segments_path.empty()) {
    SegmentFileHeader header;
    header.seed = s.config.seed;
    header.samples = st.samples;
    header.scene_fingerprint = s.loaded.scene->fingerprint();
    header.object_count = static_cast<uint32_t>(s.loaded.scene->object_count());
    header.empty_space_detection = st.empty_space.enabled;
    write_segments(config.segments_path, s.result.segments, header);
    log("viewcells: segments -> " + config.segments_path);
  }
  out.write_seconds = sw.seconds();
  if (config.measure_raw) {
    SamplerConfig same = s.config;  // every ray of exactly the samples drawn, re-casts included
    same.samples = st.samples;
    same.target_segments = 0;
    const std::vector<Ray> rays = sampled_rays(*s.loaded.scene, *s.loaded.caster, same);
    out.raw = RawRayTiming{rays.size(), s.loaded.caster->time_raw(rays)};
    const double raw_rate = out.raw->rays / out.raw->seconds;
    const double seg_rate = st.valid_segments / st.seconds;
    log("viewcells: raw Embree: " + fmt(raw_rate / 1e6, 3) + " M rays/s on the same " + std::to_string(rays.size()) +
        " rays; segments/s over half of that: " + fmt(seg_rate / (0.5 * raw_rate), 3));
  }
  return out;
}

}  // namespace viewcells::pipeline
