#include "commands.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/io/binary_file.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/generators.h"

namespace viewcells::cli {
namespace {

using nlohmann::json;

json to_json(const Vec3& v) { return json::array({v.x, v.y, v.z}); }
json to_json(const Box3& b) { return {{"min", to_json(b.lo)}, {"max", to_json(b.hi)}}; }

Box3 parse_box(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error("--view-box: '" + item + "' is not a number");
    }
  }
  if (v.size() != 6) throw Error("--view-box needs six numbers: xmin,ymin,zmin,xmax,ymax,zmax");
  Box3 b{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
  if (!is_finite(b.lo) || !is_finite(b.hi)) throw Error("--view-box has non-finite coordinates");
  if (!(b.volume() > 0)) throw Error("--view-box must have min < max on every axis");
  return b;
}

struct Common {
  int threads = 0;
  bool quiet = false;
  void log(const std::string& s) const {
    if (!quiet) std::cerr << s << '\n';
  }
};

std::string fmt(double v, int precision = 3) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(precision);
  os << v;
  return os.str();
}

std::string describe_box(const Box3& b) {
  return "[" + fmt(b.lo.x) + ", " + fmt(b.lo.y) + ", " + fmt(b.lo.z) + "] - [" + fmt(b.hi.x) + ", " +
         fmt(b.hi.y) + ", " + fmt(b.hi.z) + "]";
}

void write_json(const std::string& path, const json& j) { write_text_file(path, j.dump(2) + "\n"); }

// ------------------------------------------------------------------------------- generate

struct GenerateArgs {
  std::string kind;
  uint64_t seed = 1;
  int size = 1;
  std::string output;
};

int run_generate(const GenerateArgs& a, const Common& c) {
  GeneratorConfig config;
  config.kind = parse_generator_kind(a.kind);
  config.seed = a.seed;
  config.size = a.size;
  Stopwatch sw;
  const Scene scene = generate_scene(config);
  write_obj(scene, a.output);
  c.log("viewcells: generated " + std::string(to_string(config.kind)) + " (size " + std::to_string(a.size) +
        ", seed " + std::to_string(a.seed) + "): " + std::to_string(scene.object_count()) + " objects, " +
        std::to_string(scene.triangle_count()) + " triangles -> " + a.output + " in " + fmt(sw.seconds(), 2) + " s");
  return 0;
}

// ----------------------------------------------------------------------------------- info

struct InfoArgs {
  std::string scene;
  std::string objects = "auto";
  bool list = false;
  std::string json_path;
};

json scene_summary(const Scene& s) {
  size_t closed = 0, solid = 0;
  for (const auto& o : s.objects) {
    closed += o.closed;
    solid += o.solid();
  }
  return {{"source", s.source},
          {"triangles", s.triangle_count()},
          {"degenerate_triangles_dropped", s.degenerate_dropped},
          {"objects", s.object_count()},
          {"grouping", to_string(s.grouping)},
          {"bounds", to_json(s.bounds)},
          {"closed_objects", closed},
          {"solid_objects", solid},
          {"all_solid", s.all_solid},
          {"surface_area", s.surface_area},
          {"non_axis_aligned_area_share", s.non_axis_aligned_share()}};
}

int run_info(const InfoArgs& a, const Common& c) {
  const Scene scene = load_scene(a.scene, parse_grouping(a.objects));
  const json summary = scene_summary(scene);
  const EmptySpaceDecision esd = decide_empty_space(scene, EmptySpaceMode::kAuto);
  std::cout << "scene:              " << a.scene << '\n'
            << "triangles:          " << scene.triangle_count() << " (" << scene.degenerate_dropped
            << " degenerate dropped)\n"
            << "objects:            " << scene.object_count() << " (grouping: " << to_string(scene.grouping) << ")\n"
            << "bounds:             " << describe_box(scene.bounds) << '\n'
            << "closed objects:     " << summary["closed_objects"].get<size_t>() << '\n'
            << "solid objects:      " << summary["solid_objects"].get<size_t>()
            << " (closed, consistently oriented, outward)\n"
            << "empty space detect: " << esd.reason << '\n'
            << "non-axis-aligned:   " << fmt(100.0 * scene.non_axis_aligned_share(), 2) << "% of "
            << fmt(scene.surface_area, 1) << " surface area\n";
  if (a.list) {
    std::cout << "\n#id\ttriangles\tclosed\toriented\tsolid\tname\n";
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const ObjectInfo& o = scene.objects[i];
      std::cout << i << '\t' << o.triangle_count << '\t' << o.closed << '\t' << o.oriented << '\t' << o.solid()
                << '\t' << o.name << '\n';
    }
  }
  if (!a.json_path.empty()) {
    json j = summary;
    j["empty_space_detection"] = {{"enabled", esd.enabled}, {"reason", esd.reason}};
    json objects = json::array();
    for (const ObjectInfo& o : scene.objects)
      objects.push_back({{"name", o.name},
                         {"triangles", o.triangle_count},
                         {"bounds", to_json(o.bounds)},
                         {"closed", o.closed},
                         {"oriented", o.oriented},
                         {"solid", o.solid()}});
    j["object_list"] = std::move(objects);
    write_json(a.json_path, j);
    c.log("viewcells: wrote " + a.json_path);
  }
  return 0;
}

// --------------------------------------------------------------------------------- sample

struct SampleArgs {
  std::string scene;
  std::string objects = "auto";
  uint64_t samples = 1'000'000;
  uint64_t segments = 0;
  uint64_t seed = 1;
  std::string output;
  std::string report;
  std::string view_box;
  std::string empty_space = "auto";
  bool fast = false;
  bool measure_raw = false;
  bool segments_given = false;
  int max_recasts = 8;
};

int run_sample(const SampleArgs& a, const Common& c) {
  if (a.samples == 0) throw Error("--samples must be positive");
  if (a.segments == 0 && a.segments_given) throw Error("--segments must be positive");
  ThreadLimit threads(c.threads);
  SamplerConfig config;
  config.samples = a.samples;
  config.target_segments = a.segments;
  config.seed = a.seed;
  config.empty_space = parse_empty_space_mode(a.empty_space);
  config.max_recasts = a.max_recasts;
  config.show_progress = !c.quiet;
  if (!a.view_box.empty()) config.view_box = parse_box(a.view_box);

  Stopwatch sw;
  const Scene scene = load_scene(a.scene, parse_grouping(a.objects));
  const double load_s = sw.seconds();
  c.log("viewcells: " + a.scene + ": " + std::to_string(scene.object_count()) + " objects, " +
        std::to_string(scene.triangle_count()) + " triangles, loaded in " + fmt(load_s, 2) + " s");

  sw.restart();
  EmbreeConfig ec;
  ec.robust = !a.fast;
  const auto caster = make_embree_caster(scene, ec);
  const double bvh_s = sw.seconds();

  const EmptySpaceDecision esd = decide_empty_space(scene, config.empty_space);
  c.log("viewcells: sampling " + (a.segments ? "until " + std::to_string(a.segments) + " segments" : std::to_string(a.samples) + " samples") + ", seed " + std::to_string(a.seed) + ", " +
        std::to_string(threads.threads()) + " threads, " + caster->name() + "; view box " +
        (config.view_box.empty() ? "= scene bounds" : describe_box(config.view_box)) +
        "; empty space detection " + esd.reason);

  SamplingResult result = sample_segments(scene, *caster, config);
  const SamplingStats& st = result.stats;

  sw.restart();
  if (!a.output.empty()) {
    SegmentFileHeader header;
    header.seed = a.seed;
    header.samples = st.samples;
    header.scene_fingerprint = scene.fingerprint();
    header.object_count = static_cast<uint32_t>(scene.object_count());
    header.empty_space_detection = st.empty_space.enabled;
    write_segments(a.output, result.segments, header);
  }
  const double write_s = sw.seconds();

  const double seg_rate = st.valid_segments / st.seconds;
  c.log("viewcells: " + std::to_string(st.valid_segments) + " valid segments of " + std::to_string(st.samples) +
        " samples (" + std::to_string(st.rays) + " rays) in " + fmt(st.seconds, 2) + " s: " + fmt(seg_rate / 1e6, 3) +
        " M segments/s" + (a.output.empty() ? "" : " -> " + a.output));

  json report;
  report["command"] = "sample";
  report["scene"] = scene_summary(scene);
  report["settings"] = {{"samples", a.segments ? json(nullptr) : json(a.samples)},
                        {"target_segments", a.segments ? json(a.segments) : json(nullptr)},
                        {"seed", a.seed},
                        {"threads", threads.threads()},
                        {"object_grouping", to_string(scene.grouping)},
                        {"view_box", to_json(st.view_box)},
                        {"view_box_source", st.view_box_from_scene ? "scene bounds" : "user (--view-box)"},
                        {"ray_caster", caster->name()},
                        {"max_recasts", a.max_recasts},
                        {"batch_size", config.batch_size}};
  report["effects"] = {
      {"empty_space_detection", {{"enabled", st.empty_space.enabled}, {"reason", st.empty_space.reason}}},
      {"embree_robust_mode",
       {{"enabled", !a.fast},
        {"reason", a.fast ? "disabled by --fast: faster, but rays may slip through shared edges"
                          : "enabled by default: fewer rays slip through shared edges"}}}};
  uint64_t objects_hit = 0, max_per_object = 0;
  for (uint64_t n : st.segments_per_object) {
    objects_hit += n > 0;
    max_per_object = std::max(max_per_object, n);
  }
  report["counts"] = {{"samples", st.samples},
                      {"rays", st.rays},
                      {"recast_rays", st.recast_rays},
                      {"valid_segments", st.valid_segments},
                      {"missed_both", st.missed_both},
                      {"stuck_in_solid", st.stuck_in_solid},
                      {"outside_view_box", st.outside_view_box},
                      {"two_sided_samples", st.two_sided_samples},
                      {"objects_hit", objects_hit},
                      {"objects_never_hit", scene.object_count() - objects_hit},
                      {"max_segments_per_object", max_per_object},
                      {"segments_per_object", st.segments_per_object}};
  json timing = {{"load_seconds", load_s},
                 {"bvh_build_seconds", bvh_s},
                 {"sampling_seconds", st.seconds},
                 {"write_seconds", write_s},
                 {"segments_per_second", seg_rate},
                 {"samples_per_second", st.samples / st.seconds},
                 {"rays_per_second", st.rays / st.seconds}};
  if (a.measure_raw) {
    SamplerConfig same = config;  // every ray of exactly the samples drawn, re-casts included
    same.samples = st.samples;
    same.target_segments = 0;
    const std::vector<Ray> rays = sampled_rays(scene, *caster, same);
    const double raw_s = caster->time_raw(rays);
    const double raw_rate = rays.size() / raw_s;
    timing["raw_rays"] = rays.size();
    timing["raw_seconds"] = raw_s;
    timing["raw_rays_per_second"] = raw_rate;
    timing["segments_per_second_over_half_raw_rays_per_second"] = seg_rate / (0.5 * raw_rate);
    c.log("viewcells: raw Embree: " + fmt(raw_rate / 1e6, 3) + " M rays/s on the same " +
          std::to_string(rays.size()) + " rays; segments/s over half of that: " +
          fmt(seg_rate / (0.5 * raw_rate), 3));
  }
  report["timings"] = timing;
  if (!a.report.empty()) {
    write_json(a.report, report);
    c.log("viewcells: report -> " + a.report);
  }
  return 0;
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{
      "viewcells: builds view cells for visibility preprocessing from the visibility of the scene itself.\n"
      "Pipeline (stages come online issue by issue): generate or load a scene -> sample visibility\n"
      "segments -> (subdivide, merge, extract, compress PVS)."};
  app.require_subcommand(1);
  app.fallthrough();
  Common common;
  app.add_option("--threads", common.threads, "Worker threads (0 = all cores); results do not depend on it")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", common.quiet, "No progress bars or log lines on stderr");

  GenerateArgs gen;
  auto* g = app.add_subcommand("generate", "Write a generated test scene as OBJ (one group per object)");
  g->add_option("kind", gen.kind, "office | city | rotated-office")->required();
  g->add_option("--seed", gen.seed, "Random seed (same seed, same scene)")->capture_default_str();
  g->add_option("--size", gen.size,
                "Scale >= 1: office rooms and floors, city blocks per side (city 20 ~ 1M triangles)")
      ->capture_default_str();
  g->add_option("-o,--output", gen.output, "Output .obj file")->required();

  InfoArgs info;
  auto* i = app.add_subcommand("info", "Describe a scene: objects, triangles, bounds, closedness, axis alignment");
  i->add_option("scene", info.scene, "Scene file (.obj, .ply, .off, .stl)")->required();
  i->add_option("--objects", info.objects, "Object grouping: auto | groups | components | triangles")
      ->capture_default_str();
  i->add_flag("--list", info.list, "List every object");
  i->add_option("--json", info.json_path, "Also write the description as JSON");

  SampleArgs smp;
  auto* s = app.add_subcommand("sample", "Cast visibility segments through the view space (paper section 4.1)");
  s->add_option("scene", smp.scene, "Scene file (.obj, .ply, .off, .stl)")->required();
  auto* samples_opt = s->add_option("--samples", smp.samples, "Number of samples (two rays each)")->capture_default_str();
  s->add_option("--segments", smp.segments, "Sample until this many valid segments exist (instead of --samples)")
      ->excludes(samples_opt);
  s->add_option("--seed", smp.seed, "Random seed")->capture_default_str();
  s->add_option("-o,--output", smp.output, "Segment file to write (.vseg)");
  s->add_option("--report", smp.report, "JSON report: settings, effects enabled and why, counts, timings");
  s->add_option("--objects", smp.objects, "Object grouping: auto | groups | components | triangles")
      ->capture_default_str();
  s->add_option("--view-box", smp.view_box, "View space box xmin,ymin,zmin,xmax,ymax,zmax (default: scene bounds)");
  s->add_option("--empty-space", smp.empty_space,
                "Empty view space detection: auto (only for closed, outward-oriented scenes) | on | off")
      ->capture_default_str();
  s->add_option("--max-recasts", smp.max_recasts, "Re-casts per sample when empty space detection is on")
      ->capture_default_str();
  s->add_flag("--fast", smp.fast, "Embree without robust mode (faster, may leak through edges)");
  s->add_flag("--measure-raw", smp.measure_raw,
              "Also cast the same rays (re-casts included) through Embree alone; report raw_rays_per_second");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (*g) return run_generate(gen, common);
    if (*i) return run_info(info, common);
    if (*s) {
      smp.segments_given = s->count("--segments") > 0;
      return run_sample(smp, common);
    }
  } catch (const Error& e) {
    std::cerr << "viewcells: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "viewcells: error: " << e.what() << '\n';
    return 2;
  }
  return 0;
}

}  // namespace viewcells::cli
