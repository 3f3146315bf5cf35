#include "viewcells/pipeline/sampling.h"

#include <cctype>
#include <filesystem>

#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/q3/play.h"
#include "viewcells/q3/view_space.h"
#include "viewcells/sampling/segments.h"

namespace viewcells::pipeline {

bool is_q3_map(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".bsp";
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
    if (is_q3_map(source.path)) out.map = std::make_shared<const Q3Map>(read_q3bsp(source.path));
  }
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

void use_map_view_space(LoadedScene& s, SamplerConfig& config) {
  if (!s.map) return;
  std::shared_ptr<const Q3Map> map = s.map;
  config.view_space = [map](const Vec3& p) { return q3_in_view_space(*map, p); };
  if (config.view_box.empty()) config.view_box = q3_view_box(*map);
  size_t open = 0;
  for (const Q3Leaf& l : map->leaves) open += l.cluster >= 0;
  s.view_space = "the map's non-solid space (" + std::to_string(open) + " of " + std::to_string(map->leaves.size()) +
                 " leaves): sample origins in solid leaves are drawn again";
}

void use_map_view_space(const std::shared_ptr<const Q3Map>& map, AgvsConfig& config) {
  if (!map) return;
  config.view_space = [map](const Vec3& p) { return q3_in_view_space(*map, p); };
}

Box3 covered_view_box(const Q3Map* map, const Box3& box) {
  Box3 out = box;
  if (map) out.extend(q3_cover_box(*map));
  return out;
}

const PlaySpace& play_space(LoadedScene& s) {
  if (!s.map) throw Error("the play space needs a Quake 3 map");
  if (!s.play)
    s.play = std::make_shared<const PlaySpace>(q3_play_space(*s.map, *s.scene, *s.caster, PlaySpaceConfig{}));
  return *s.play;
}

void use_play_view_space(LoadedScene& s, AgvsConfig& config) {
  const std::vector<bool>& leaves_of_play = play_space(s).leaves;  // s.play holds it from here on
  const std::shared_ptr<const std::vector<bool>> play(s.play, &leaves_of_play);  // shares its ownership
  std::shared_ptr<const Q3Map> map = s.map;
  // The play leaves' bounds, drawn by volume: a point of leaf l's bounds counts when it lies in
  // l (and outside its detail brushes), so the points are uniform over the play leaves however
  // their bounds overlap.
  const Subdivision q3 = q3_subdivision(*map, q3_view_box(*map));
  const int32_t inner = static_cast<int32_t>(map->nodes.size());
  struct Leaf {
    double upto;  ///< the bounds' volume of the leaves so far, this one's included
    int32_t leaf;
    Box3 bounds;
  };
  auto leaves = std::make_shared<std::vector<Leaf>>();
  double total = 0;
  for (int32_t l = 0; l < static_cast<int32_t>(play->size()); ++l) {
    if (!(*play)[l] || q3.cells[inner + l].empty()) continue;
    const Box3 b = q3.cells[inner + l].bounds();
    if (!(b.volume() > 0)) continue;
    leaves->push_back({total += b.volume(), l, b});
  }
  if (leaves->empty()) throw Error(map->path, 0, "the play space is empty: no leaf a player's eye can be in");
  config.view_point_map = [map, leaves, total](double u0, double u1, double u2) {
    const double at = u0 * total;
    const auto it = std::lower_bound(leaves->begin(), leaves->end(), at,
                                     [](const Leaf& x, double v) { return x.upto <= v; });
    const Leaf& x = it == leaves->end() ? leaves->back() : *it;
    const double from = x.upto - x.bounds.volume();
    const double f = std::clamp((at - from) / x.bounds.volume(), 0.0, 1.0);
    const Vec3 e = x.bounds.extent();
    const Vec3 p{x.bounds.lo.x + e.x * f, x.bounds.lo.y + e.y * u1, x.bounds.lo.z + e.z * u2};
    if (map->leaf_at(p) != x.leaf || !q3_in_view_space(*map, p)) return Vec3{std::nan(""), 0, 0};
    return p;
  };
  // REF draws its points in cells, and reports ask whether the points are restricted.
  config.view_space = [map, play](const Vec3& p) { return (*play)[map->leaf_at(p)] && q3_in_view_space(*map, p); };
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
  use_map_view_space(out.loaded, out.config);
  const SamplerConfig& c = out.config;
  const EmptySpaceDecision esd = decide_empty_space(*out.loaded.scene, c.empty_space);
  log("viewcells: sampling " +
      (c.target_segments ? "until " + std::to_string(c.target_segments) + " segments"
                         : std::to_string(c.samples) + " samples") +
      ", seed " + std::to_string(c.seed) + ", " + std::to_string(out.threads) + " threads, " +
      out.loaded.caster->name() + "; view box " + (c.view_box.empty() ? "= scene bounds" : describe_box(c.view_box)) +
      "; view space " + out.loaded.view_space + "; empty space detection " + esd.reason);
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
