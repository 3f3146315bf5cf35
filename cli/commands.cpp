#include "commands.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "viewcells/agvs/agvs.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/bsp/subdivision_io.h"
#include "viewcells/core/error.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/io/binary_file.h"
#include "viewcells/eval/compare.h"
#include "viewcells/io/q3bsp.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/merge/merge.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/q3/compare.h"
#include "viewcells/q3/view_space.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/generators.h"

namespace viewcells::cli {
namespace {

using nlohmann::json;

json to_json(const Vec3& v) { return json::array({v.x, v.y, v.z}); }
json to_json(const Box3& b) { return {{"min", to_json(b.lo)}, {"max", to_json(b.hi)}}; }

/// Comma-separated numbers of option `option`; throws Error naming the option.
std::vector<double> parse_numbers(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error(option + ": '" + item + "' is not a number");
    }
    if (!std::isfinite(v.back())) throw Error(option + ": '" + item + "' is not finite");
  }
  return v;
}

Box3 parse_box(const std::string& text) {
  const std::vector<double> v = parse_numbers(text, "--view-box");
  if (v.size() != 6) throw Error("--view-box needs six numbers: xmin,ymin,zmin,xmax,ymax,zmax");
  Box3 b{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
  if (!(b.volume() > 0)) throw Error("--view-box must have min < max on every axis");
  return b;
}

/// A whole number from lo to hi, written without sign or exponent (CLI11 alone reads "-1" into
/// an unsigned option as 2^64 - 1).
CLI::Validator whole(uint64_t lo, uint64_t hi) {
  return CLI::Validator(
      [lo, hi](const std::string& text) -> std::string {
        uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < lo || v > hi)
          return "'" + text + "' is not allowed: give a whole number from " + std::to_string(lo) + " to " +
                 std::to_string(hi);
        return "";
      },
      "INT in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

/// A finite number above zero.
CLI::Validator positive() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        try {
          size_t used = 0;
          const double v = std::stod(text, &used);
          if (used == text.size() && std::isfinite(v) && v > 0) return "";
        } catch (const std::exception&) {
        }
        return "'" + text + "' is not allowed: give a number above 0";
      },
      "NUMBER > 0");
}

constexpr uint64_t kMaxSamples = uint64_t{1} << 40;  // a trillion rays: beyond any one machine's memory
constexpr uint64_t kMaxCells = 10'000'000;

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

/// Before any work: refuses an output that is also an input or another output, or that exists
/// as something other than a regular file (a device, FIFO, directory or symbolic link). Empty
/// names are options not given.
void check_files(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  namespace fs = std::filesystem;
  auto key = [](const std::string& p) {
    std::error_code ec;
    const fs::path k = fs::weakly_canonical(fs::absolute(p), ec);
    return ec ? fs::absolute(p).lexically_normal().string() : k.string();
  };
  std::vector<std::pair<std::string, std::string>> seen;  // (canonical, as given)
  for (const std::string& in : inputs)
    if (!in.empty()) seen.push_back({key(in), in});
  const size_t input_count = seen.size();
  for (const std::string& out : outputs) {
    if (out.empty()) continue;
    check_output_target(out);
    const std::string k = key(out);
    for (size_t i = 0; i < seen.size(); ++i)
      if (seen[i].first == k)
        throw Error(out + ": is " + (i < input_count ? "an input of this command" : "given for two outputs") +
                    " (" + seen[i].second + "); write it elsewhere");
    seen.push_back({k, out});
  }
}

/// Reports say which Embree ISA cast their rays: results are bit-identical only for the same one.
void write_json(const std::string& path, json j) {
  if (j.is_object()) j["embree_isa"] = embree_isa();
  write_text_file(path, j.dump(2) + "\n");
}

// ------------------------------------------------------------------------------- generate

struct GenerateArgs {
  std::string kind;
  uint64_t seed = 1;
  int size = 1;
  std::string output;
};

int run_generate(const GenerateArgs& a, const Common& c) {
  check_files({}, {a.output});

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

bool is_q3_map(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".bsp";
}

int run_info(const InfoArgs& a, const Common& c) {
  check_files({a.scene}, {a.json_path});

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
  json map_json;
  if (is_q3_map(a.scene)) {
    // What the Quake 3 map itself holds besides the geometry.
    const Q3Map map = read_q3bsp(a.scene);
    Q3MeshStats st;
    q3_world_mesh(map, {}, &st);
    size_t solid_leaves = 0;
    for (const Q3Leaf& l : map.leaves) solid_leaves += l.cluster < 0;
    std::cout << "quake 3 map:        IBSP version " << map.version << ", " << map.shaders.size() << " shaders, "
              << map.nodes.size() << " nodes, " << map.leaves.size() << " leaves (" << solid_leaves << " solid)\n"
              << "world surfaces:     " << st.surfaces[0] << " opaque, " << st.surfaces[1] << " sky (they close "
              << "the map for rays but are not rendered: no render cost), " << st.surfaces[2] << " water/fog/translucent (rendered, seen through: they stop no ray), " << st.surfaces[3]
              << " nodraw/hint/skip/flare (left out); " << st.patches << " patches tessellated at level 4\n"
              << "solid brushes:      " << st.brush_hulls << " of " << map.world_brush_count
              << " as hulls 0.5 units inside their sides (occlude, not rendered)\n"
              << "visibility:         "
              << (map.has_visibility() ? std::to_string(map.cluster_count) + " clusters, rows of " +
                                             std::to_string(map.cluster_bytes) + " bytes (q3map2's PVS)"
                                       : std::string("none (the map was not vis-compiled)"))
              << "\nspawn points:       " << st.spawn_points << '\n';
    map_json = {{"version", map.version},
                {"leaves", map.leaves.size()},
                {"solid_leaves", solid_leaves},
                {"surfaces", {{"opaque", st.surfaces[0]}, {"sky", st.surfaces[1]}, {"non_occluding", st.surfaces[2]},
                              {"skipped", st.surfaces[3]}, {"patches", st.patches}}},
                {"brush_hulls", st.brush_hulls},
                {"clusters", map.cluster_count},
                {"cluster_row_bytes", map.cluster_bytes},
                {"spawn_points", st.spawn_points}};
  }
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
    if (!map_json.is_null()) j["quake3"] = map_json;
    write_json(a.json_path, j);
    c.log("viewcells: wrote " + a.json_path);
  }
  return 0;
}

// --------------------------------------------------------------------------------- sample

/// Scene and sampling options shared by `sample` and `build`.
struct SampleArgs {
  std::string scene;
  std::string objects = "auto";
  uint64_t samples = 1'000'000;
  uint64_t segments = 0;
  bool segments_given = false;
  uint64_t seed = 1;
  std::string view_box;
  std::string empty_space = "auto";
  bool fast = false;
  int max_recasts = 8;
};

void add_sampling_options(CLI::App* cmd, SampleArgs& a) {
  cmd->add_option("scene", a.scene, "Scene file (.obj, .ply, .off, .stl)")->required();
  auto* samples_opt = cmd->add_option("--samples", a.samples, "Number of samples (two rays each)")
                          ->capture_default_str()
                          ->check(whole(1, kMaxSamples));
  cmd->add_option("--segments", a.segments, "Sample until this many valid segments exist (instead of --samples)")
      ->check(whole(1, kMaxSamples))
      ->excludes(samples_opt);
  cmd->add_option("--seed", a.seed, "Random seed (same seed, same result for any --threads)")->capture_default_str();
  cmd->add_option("--objects", a.objects, "Object grouping: auto | groups | components | triangles")
      ->capture_default_str();
  cmd->add_option("--view-box", a.view_box, "View space box xmin,ymin,zmin,xmax,ymax,zmax (default: scene bounds)");
  cmd->add_option("--empty-space", a.empty_space,
                  "Empty view space detection: auto (only for closed, outward-oriented scenes) | on | off")
      ->capture_default_str();
  cmd->add_option("--max-recasts", a.max_recasts, "Re-casts per sample when empty space detection is on")
      ->capture_default_str();
  cmd->add_flag("--fast", a.fast, "Embree without robust mode (faster, may leak through edges)");
}

/// What loading and sampling produced, with timings.
struct Sampled {
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  std::shared_ptr<const Q3Map> map;  ///< the Quake 3 map, when the scene is one
  SamplerConfig config;
  SamplingResult result;
  double load_s = 0, bvh_s = 0;
  std::string view_space = "the whole view box";  ///< where sample origins are drawn, in words
};

/// A Quake 3 map's view space is its non-solid space: sample origins are drawn there, and the
/// view box defaults to the bounds of its non-solid leaves.
void use_map_view_space(Sampled& s, SamplerConfig& config) {
  if (!s.map) return;
  std::shared_ptr<const Q3Map> map = s.map;
  config.view_space = [map](const Vec3& p) { return q3_in_view_space(*map, p); };
  if (config.view_box.empty()) config.view_box = q3_view_box(*map);
  size_t open = 0;
  for (const Q3Leaf& l : map->leaves) open += l.cluster >= 0;
  s.view_space = "the map's non-solid space (" + std::to_string(open) + " of " + std::to_string(map->leaves.size()) +
                 " leaves): sample origins in solid leaves are drawn again";
}

SamplerConfig sampler_config(const SampleArgs& a, const Common& c) {
  if (a.samples == 0) throw Error("--samples must be positive");
  if (a.segments == 0 && a.segments_given) throw Error("--segments must be positive");
  SamplerConfig config;
  config.samples = a.samples;
  config.target_segments = a.segments;
  config.seed = a.seed;
  config.empty_space = parse_empty_space_mode(a.empty_space);
  config.max_recasts = a.max_recasts;
  config.show_progress = !c.quiet;
  if (!a.view_box.empty()) config.view_box = parse_box(a.view_box);
  return config;
}

/// Loads the scene and builds the ray caster (into out.scene, out.caster).
void load_for_sampling(const SampleArgs& a, const Common& c, Sampled& out) {
  Stopwatch sw;
  out.scene = load_scene(a.scene, parse_grouping(a.objects));
  if (is_q3_map(a.scene)) out.map = std::make_shared<const Q3Map>(read_q3bsp(a.scene));
  out.load_s = sw.seconds();
  c.log("viewcells: " + a.scene + ": " + std::to_string(out.scene.object_count()) + " objects, " +
        std::to_string(out.scene.triangle_count()) + " triangles, loaded in " + fmt(out.load_s, 2) + " s");
  sw.restart();
  EmbreeConfig ec;
  ec.robust = !a.fast;
  out.caster = make_embree_caster(out.scene, ec);
  out.bvh_s = sw.seconds();
}

Sampled load_and_sample(const SampleArgs& a, const Common& c, int threads) {
  Sampled out;
  out.config = sampler_config(a, c);
  load_for_sampling(a, c, out);
  use_map_view_space(out, out.config);
  const SamplerConfig& config = out.config;
  const EmptySpaceDecision esd = decide_empty_space(out.scene, config.empty_space);
  c.log("viewcells: sampling " +
        (a.segments ? "until " + std::to_string(a.segments) + " segments" : std::to_string(a.samples) + " samples") +
        ", seed " + std::to_string(a.seed) + ", " + std::to_string(threads) + " threads, " + out.caster->name() +
        "; view box " + (config.view_box.empty() ? "= scene bounds" : describe_box(config.view_box)) +
        "; view space " + out.view_space + "; empty space detection " + esd.reason);
  out.result = sample_segments(out.scene, *out.caster, config);
  const SamplingStats& st = out.result.stats;
  c.log("viewcells: " + std::to_string(st.valid_segments) + " valid segments of " + std::to_string(st.samples) +
        " samples (" + std::to_string(st.rays) + " rays) in " + fmt(st.seconds, 2) + " s: " +
        fmt(st.valid_segments / st.seconds / 1e6, 3) + " M segments/s");
  return out;
}

json sampling_report(const SampleArgs& a, const Sampled& s, int threads) {
  const SamplingStats& st = s.result.stats;
  json report;
  report["scene"] = scene_summary(s.scene);
  report["settings"] = {{"samples", a.segments ? json(nullptr) : json(a.samples)},
                        {"target_segments", a.segments ? json(a.segments) : json(nullptr)},
                        {"seed", a.seed},
                        {"threads", threads},
                        {"object_grouping", to_string(s.scene.grouping)},
                        {"view_box", to_json(st.view_box)},
                        {"view_box_source", st.view_box_from_scene ? "scene bounds"
                                            : (s.map && a.view_box.empty() ? "the map's non-solid leaves"
                                                                           : "user (--view-box)")},
                        {"view_space", s.view_space},
                        {"ray_caster", s.caster->name()},
                        {"max_recasts", a.max_recasts},
                        {"batch_size", s.config.batch_size}};
  report["effects"] = {
      {"empty_space_detection", {{"enabled", st.empty_space.enabled}, {"reason", st.empty_space.reason}}},
      {"embree_robust_mode",
       {{"enabled", !a.fast},
        {"reason", a.fast ? "disabled by --fast: faster, but rays may slip through shared edges"
                          : "enabled by default: fewer rays slip through shared edges"}}},
      {"see_through_objects",
       {{"enabled", st.see_through_objects > 0},
        {"reason", st.see_through_objects
                       ? std::to_string(st.see_through_objects) +
                             " objects are seen through (water, glass, fog): they stop no ray, and every segment "
                             "crossing one sees it"
                       : std::string("every object occludes")}}},
      {"restricted_view_space", {{"enabled", static_cast<bool>(s.config.view_space)}, {"reason", s.view_space}}}};
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
                      {"rejected_origins", st.rejected_origins},
                      {"see_through_objects", st.see_through_objects},
                      {"see_through_segments", st.see_through_segments},
                      {"see_through_rays", st.see_through_rays},
                      {"objects_hit", objects_hit},
                      {"objects_never_hit", s.scene.object_count() - objects_hit},
                      {"max_segments_per_object", max_per_object},
                      {"segments_per_object", st.segments_per_object}};
  report["timings"] = {{"load_seconds", s.load_s},
                       {"bvh_build_seconds", s.bvh_s},
                       {"sampling_seconds", st.seconds},
                       {"segments_per_second", st.valid_segments / st.seconds},
                       {"samples_per_second", st.samples / st.seconds},
                       {"rays_per_second", st.rays / st.seconds}};
  return report;
}

struct SampleOnlyArgs {
  std::string output, report;
  bool measure_raw = false;
};

int run_sample(const SampleArgs& a, const SampleOnlyArgs& o, const Common& c) {
  check_files({a.scene}, {o.output, o.report});

  ThreadLimit threads(c.threads);
  const Sampled s = load_and_sample(a, c, threads.threads());
  const SamplingStats& st = s.result.stats;
  Stopwatch sw;
  if (!o.output.empty()) {
    SegmentFileHeader header;
    header.seed = a.seed;
    header.samples = st.samples;
    header.scene_fingerprint = s.scene.fingerprint();
    header.object_count = static_cast<uint32_t>(s.scene.object_count());
    header.empty_space_detection = st.empty_space.enabled;
    write_segments(o.output, s.result.segments, header);
    c.log("viewcells: segments -> " + o.output);
  }
  json report = sampling_report(a, s, threads.threads());
  report["command"] = "sample";
  report["timings"]["write_seconds"] = sw.seconds();
  if (o.measure_raw) {
    SamplerConfig same = s.config;  // every ray of exactly the samples drawn, re-casts included
    same.samples = st.samples;
    same.target_segments = 0;
    const std::vector<Ray> rays = sampled_rays(s.scene, *s.caster, same);
    const double raw_s = s.caster->time_raw(rays);
    const double raw_rate = rays.size() / raw_s;
    const double seg_rate = st.valid_segments / st.seconds;
    report["timings"]["raw_rays"] = rays.size();
    report["timings"]["raw_seconds"] = raw_s;
    report["timings"]["raw_rays_per_second"] = raw_rate;
    report["timings"]["segments_per_second_over_half_raw_rays_per_second"] = seg_rate / (0.5 * raw_rate);
    c.log("viewcells: raw Embree: " + fmt(raw_rate / 1e6, 3) + " M rays/s on the same " + std::to_string(rays.size()) +
          " rays; segments/s over half of that: " + fmt(seg_rate / (0.5 * raw_rate), 3));
  }
  if (!o.report.empty()) {
    write_json(o.report, report);
    c.log("viewcells: report -> " + o.report);
  }
  return 0;
}

// ---------------------------------------------------------------------------------- build

struct BuildArgs {
  std::string output, report, mesh, slice_png;
  uint32_t max_cells = 1000;
  bool no_ga = false;
  bool ga = false;
  bool no_merge = false;
  uint32_t ga_candidates = 150;
  uint32_t axis_candidates = 200;
  double min_reduction = 1e-6;
  double cost_a = 100, cost_b = 1, cost_c = 0;
  std::string screen = "1024x768";
  double fov = 90;
  double slice_z = NAN;
  int slice_width = 1024;
  std::string density_band;
};

void parse_screen(const std::string& text, CostModel& model) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
    throw Error("--screen needs WIDTHxHEIGHT, e.g. 1024x768 (got '" + text + "')");
  model.screen_width = w;
  model.screen_height = h;
}

HeightBandDensity parse_density_band(const std::string& text) {
  HeightBandDensity d;
  if (text.empty()) return d;
  const std::vector<double> v = parse_numbers(text, "--density-band");
  if (v.size() < 2 || v.size() > 3) throw Error("--density-band needs zlo,zhi[,outside_weight]");
  d.enabled = true;
  d.lo = v[0];
  d.hi = v[1];
  if (v.size() == 3) d.outside = v[2];
  if (!(d.lo < d.hi) || !(d.outside >= 0)) throw Error("--density-band needs zlo < zhi and outside_weight >= 0");
  return d;
}

void write_views(const Subdivision& s, const Scene* scene, const std::string& mesh, const std::string& png,
                 double slice_z, int width, const Common& c, const CellView* view = nullptr) {
  if (!mesh.empty()) {
    write_cells_ply(mesh, s, view);
    c.log("viewcells: cells -> " + mesh + " (coloured by render cost)");
  }
  if (!png.empty()) {
    const double z = std::isnan(slice_z) ? 0.5 * (s.view_box.lo.z + s.view_box.hi.z) : slice_z;
    write_slice_png(png, s, z, width, scene, view);
    c.log("viewcells: slice at z = " + fmt(z, 3) + " -> " + png);
  }
}

int run_build(const SampleArgs& a, const BuildArgs& b, const Common& c) {
  check_files({a.scene}, {b.output, b.report, b.mesh, b.slice_png});

  ThreadLimit threads(c.threads);
  CostModel model;
  model.a = b.cost_a;
  model.b = b.cost_b;
  model.c = b.cost_c;
  parse_screen(b.screen, model);
  model.fov_degrees = b.fov;
  model.validate();  // before the sampling, not after
  const HeightBandDensity density = parse_density_band(b.density_band);
  const Sampled s = load_and_sample(a, c, threads.threads());
  if (!std::isnan(b.slice_z) && !(b.slice_z >= s.result.segments.view_box.lo.z && b.slice_z <= s.result.segments.view_box.hi.z))
    throw Error("--slice-z " + fmt(b.slice_z) + " lies outside the view space (z from " + fmt(s.result.segments.view_box.lo.z) + " to " +
                fmt(s.result.segments.view_box.hi.z) + ")");

  SubdivisionConfig config;
  config.max_cells = b.max_cells;
  config.geometry_aligned = b.no_ga ? GeometryAlignedMode::kOff : (b.ga ? GeometryAlignedMode::kOn : GeometryAlignedMode::kAuto);
  config.ga_candidates = b.ga_candidates;
  config.max_axis_candidates = b.axis_candidates;
  config.min_reduction = b.min_reduction;
  config.density = density;
  config.seed = a.seed;
  config.show_progress = !c.quiet;
  std::string ga_reason;
  use_geometry_aligned(s.scene, config, ga_reason);
  c.log("viewcells: subdividing to at most " + std::to_string(b.max_cells) + " cells; geometry-aligned candidates " +
        ga_reason);
  c.log("viewcells: pixel cost term " + model.describe_pixel_term());
  Subdivision sub = subdivide(s.scene, s.result.segments, model, config);
  c.log("viewcells: " + std::to_string(sub.leaf_count()) + " cells in " + fmt(sub.stats.seconds, 2) +
        " s, render cost " + fmt(sub.initial_cost, 1) + " -> " + fmt(sub.cost(), 1) + " (" + sub.stats.stop_reason + ")");
  if (s.map && !density.enabled) {
    // p(i) over the map's non-solid space: merging, extraction and the file use these weights.
    weight_by_view_space(sub, q3_subdivision(*s.map, sub.view_box));
    c.log("viewcells: cells weighted by their volume in the map's non-solid space");
  }

  SubdivisionFile file;
  file.leaf_pvs = leaf_pvs(sub, s.result.segments);
  if (!b.no_merge) {
    MergeConfig mc;
    mc.show_progress = !c.quiet;
    c.log("viewcells: merging " + std::to_string(sub.leaf_count()) + " cells into a merge history");
    file.history = merge_cells(s.scene, partition_from_subdivision(sub, file.leaf_pvs), model, mc);
    c.log("viewcells: merged in " + fmt(file.history->stats.seconds, 2) + " s (" +
          std::to_string(file.history->stats.evaluations) + " pair costs, " +
          std::to_string(file.history->stats.stale) + " stale queue entries skipped)");
  }
  Stopwatch sw;
  file.cost_model = model;
  file.scene_fingerprint = s.scene.fingerprint();
  file.object_count = static_cast<uint32_t>(s.scene.object_count());
  for (const ObjectInfo& o : s.scene.objects) file.object_names.push_back(o.name);
  if (!b.output.empty()) {
    file.subdivision = sub;
    file.subdivision.segments.clear();
    file.subdivision.cells.clear();
    write_subdivision(b.output, file);
    c.log("viewcells: hierarchy -> " + b.output);
  }
  const double write_s = sw.seconds();
  sw.restart();
  write_views(sub, &s.scene, b.mesh, b.slice_png, b.slice_z, b.slice_width, c);
  const double views_s = sw.seconds();

  json report = sampling_report(a, s, threads.threads());
  report["command"] = "build";
  report["settings"]["max_cells"] = b.max_cells;
  report["settings"]["axis_candidates_per_axis"] = b.axis_candidates;
  report["settings"]["ga_candidates"] = b.ga_candidates;
  report["settings"]["min_reduction"] = b.min_reduction;
  report["settings"]["cost_model"] = {{"a", model.a}, {"b", model.b}, {"c", model.c}};
  if (model.pixel_term())
    report["settings"]["cost_model"]["screen"] = {
        {"width", model.screen_width}, {"height", model.screen_height}, {"fov_degrees", model.fov_degrees}};
  report["effects"]["geometry_aligned_candidates"] = {{"enabled", sub.stats.geometry_aligned},
                                                      {"reason", sub.stats.geometry_aligned_reason}};
  report["effects"]["pixel_cost_term"] = {{"enabled", model.pixel_term()}, {"reason", model.describe_pixel_term()}};
  report["effects"]["viewpoint_density"] =
      config.density.enabled
          ? json{{"enabled", true},
                 {"reason", "--density-band: weight 1 for " + fmt(config.density.lo, 2) + " <= z <= " +
                                fmt(config.density.hi, 2) + ", " + fmt(config.density.outside, 3) + " elsewhere"}}
          : json{{"enabled", false}, {"reason", "uniform: p(i) = V_i / V (no --density-band)"}};
  json curve = json::array();
  for (size_t cells = 1; cells <= sub.leaf_count(); cells *= 2)
    curve.push_back({{"cells", cells}, {"cost", cells == 1 ? sub.initial_cost : sub.splits[cells - 2].cost_after}});
  report["subdivision"] = {{"cells", sub.leaf_count()},
                           {"initial_cost", sub.initial_cost},
                           {"final_cost", sub.cost()},
                           {"cost_at_power_of_two_cells", curve},
                           {"axis_candidates_evaluated", sub.stats.axis_candidates},
                           {"geometry_candidates_evaluated", sub.stats.geometry_candidates},
                           {"sliver_splits_refused", sub.stats.slivers_refused},
                           {"stop_reason", sub.stats.stop_reason}};
  report["final_cost"] = sub.cost();
  if (file.history) {
    const MergeHistory& h = *file.history;
    json merged = json::array();
    for (size_t cells = 1; cells <= h.leaf_count; cells *= 2)
      if (cells >= h.min_cells()) merged.push_back({{"cells", cells}, {"cost", h.cost_with(cells)}});
    report["merge"] = {{"cells_from", h.leaf_count},
                       {"cells_to", h.min_cells()},
                       {"cost_at_power_of_two_cells", merged},
                       {"pair_costs_evaluated", h.stats.evaluations},
                       {"stale_entries_skipped", h.stats.stale}};
    report["timings"]["merge_seconds"] = h.stats.seconds;
  }
  report["effects"]["merging"] = b.no_merge ? json{{"enabled", false}, {"reason", "--no-merge"}}
                                            : json{{"enabled", true}, {"reason", "default: the merge history is built"}};
  report["timings"]["subdivision_seconds"] = sub.stats.seconds;
  report["timings"]["write_seconds"] = write_s;
  report["timings"]["export_seconds"] = views_s;
  if (!b.report.empty()) {
    write_json(b.report, report);
    c.log("viewcells: report -> " + b.report);
  }
  return 0;
}

// --------------------------------------------------------------------------------- export

struct ExportArgs {
  std::string input, mesh, png, scene;
  double slice_z = NAN;
  int width = 1024;
};

int run_export(const ExportArgs& e, const Common& c) {
  check_files({e.input, e.scene}, {e.mesh, e.png});

  if (e.mesh.empty() && e.png.empty()) throw Error("nothing to export: give --mesh and/or --slice-png");
  SubdivisionFile file = read_subdivision(e.input);
  rebuild_cells(file.subdivision);
  c.log("viewcells: " + e.input + ": " + std::to_string(file.subdivision.leaf_count()) + " cells, render cost " +
        fmt(file.subdivision.cost(), 1));
  std::unique_ptr<Scene> scene;
  if (!e.scene.empty()) {
    scene = std::make_unique<Scene>(load_scene(e.scene));
    if (scene->fingerprint() != file.scene_fingerprint)
      c.log("viewcells: warning: " + e.scene + " is not the scene these cells were built from");
  }
  write_views(file.subdivision, scene.get(), e.mesh, e.png, e.slice_z, e.width, c);
  return 0;
}

// -------------------------------------------------------------------------------- compare

struct CompareArgs {
  std::string methods = "av-m,av-s,kd-casm,kd-lasm,kd-vt,kd-vt-star,bsp";
  bool methods_given = false;
  uint32_t max_cells = 1000;
  bool max_cells_given = false;
  uint64_t eval_samples = 0;
  uint64_t eval_seed = 0;
  uint32_t histogram_cells = 0;
  double cost_a = 100, cost_b = 1;
  bool no_ga = false;
  uint32_t axis_candidates = 200;
  uint32_t ga_candidates = 150;
  std::string output;
};

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

bool has_point(const CostCurve& c, uint32_t n) { return std::binary_search(c.cells.begin(), c.cells.end(), n); }

/// The q3map2 part of compare's summary; writes every excluded-but-seen object to
/// DIR/excluded.csv and logs the headline numbers.
json q3_report(const Q3Comparison& q, const Scene& scene, const Q3Map& map, const std::string& dir, const Common& c) {
  std::string csv = "cluster,object,name,cause,ax,ay,az,bx,by,bz\n";
  const SegmentSet& eval = q.ours.evaluation_segments;
  for (const Q3Excluded& e : q.excluded) {
    char line[512];
    std::snprintf(line, sizeof line, "%d,%u,\"%s\",%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", e.cluster, e.object,
                  scene.objects[e.object].name.c_str(), e.cause.c_str(), eval.ax[e.segment], eval.ay[e.segment],
                  eval.az[e.segment], eval.bx[e.segment], eval.by[e.segment], eval.bz[e.segment]);
    csv += line;
  }
  write_text_file(dir + "/excluded.csv", csv);
  const bool reached = std::isfinite(q.avm_cost_at_clusters);
  const double ours_bytes = static_cast<double>(q.ours_compressed_bytes);
  c.log("viewcells: q3map2: " + std::to_string(q.cluster_count) + " clusters, evaluated cost " +
        fmt(q.clusters.cost, 1) + "; AV-M at " + std::to_string(q.cluster_count) + " cells " +
        (reached ? fmt(q.avm_cost_at_clusters, 1) + " (" + fmt(q.avm_cost_at_clusters / q.clusters.cost, 3) + " x)"
                 : std::string("not reached")) +
        "; AV-M matches q3map2 from " +
        (q.avm_cells_to_match ? std::to_string(q.avm_cells_to_match) + " cells" : std::string("no cell count built")));
  c.log("viewcells: q3map2: PVS size ratio ours / q3map2 " + fmt(q.mean_pvs_ratio, 3) + "; " +
        std::to_string(q.excluded.size()) + " objects seen from clusters q3map2 excludes them from (" + dir +
        "/excluded.csv); storage: q3map2 rows " + std::to_string(q.q3_row_bytes) + " B, ours " +
        std::to_string(q.ours_compressed_bytes) + " B (" + fmt(ours_bytes / std::max<double>(1, q.q3_row_bytes), 2) +
        " x)");
  json causes = json::object();
  for (const auto& [cause, n] : q.excluded_by_cause) causes[cause] = n;
  return {{"map", map.path},
          {"clusters", q.cluster_count},
          {"q3map2_cost", q.clusters.cost},
          {"av_m_cost_at_clusters", reached ? json(q.avm_cost_at_clusters) : json(nullptr)},
          {"av_m_cost_ratio", reached ? json(q.avm_cost_at_clusters / q.clusters.cost) : json(nullptr)},
          {"av_m_cells_to_match", q.avm_cells_to_match ? json(q.avm_cells_to_match) : json(nullptr)},
          {"pvs_size_ratio", q.mean_pvs_ratio},
          {"pvs_entries", {{"ours", q.ours_entries}, {"q3map2", q.q3_entries}}},
          {"excluded_but_seen", q.excluded.size()},
          {"excluded_by_cause", causes},
          {"storage_bytes",
           {{"q3map2_rows", q.q3_row_bytes},
            {"q3map2_leaf_surface_lists", q.q3_leaf_surface_bytes},
            {"ours_compressed", q.ours_compressed_bytes},
            {"ours_rle_rows", q.ours_rle_bytes}}},
          {"build_seconds", q.build_seconds}};
}

int run_compare(const SampleArgs& a, const CompareArgs& ca, const Common& c) {
  ThreadLimit threads(c.threads);
  CompareConfig config;
  config.methods = split_list(ca.methods);
  // q3-clusters is not built but read from the map: compare_with_q3map2 adds it.
  const auto q3_entry = std::find(config.methods.begin(), config.methods.end(), "q3-clusters");
  bool with_q3 = q3_entry != config.methods.end();
  if (with_q3) config.methods.erase(q3_entry);
  if (!ca.methods_given && is_q3_map(a.scene)) {
    config.methods = {"av-m", "av-s", "kd-casm"};
    with_q3 = true;
  }
  if (with_q3 && !is_q3_map(a.scene)) throw Error("q3-clusters needs a Quake 3 map (.bsp) as the scene");
  // On a map, by default three times as many cells as the map has clusters (0 below).
  config.max_cells = with_q3 && !ca.max_cells_given ? 0 : ca.max_cells;
  config.construction = sampler_config(a, c);
  config.evaluation = config.construction;
  config.evaluation.target_segments = 0;
  config.evaluation.samples = ca.eval_samples ? ca.eval_samples : 4 * a.samples;
  config.evaluation.seed = ca.eval_seed ? ca.eval_seed : a.seed + 1'000'003;
  config.model.a = ca.cost_a;
  config.model.b = ca.cost_b;
  config.model.validate();
  config.subdivision.seed = a.seed;
  config.subdivision.geometry_aligned = ca.no_ga ? GeometryAlignedMode::kOff : GeometryAlignedMode::kAuto;
  config.subdivision.max_axis_candidates = ca.axis_candidates;
  config.subdivision.ga_candidates = ca.ga_candidates;
  config.histogram_cells = ca.histogram_cells;
  config.show_progress = !c.quiet;
  check_methods(config.methods);  // before the output directory is made
  std::filesystem::create_directories(ca.output);
  Sampled loaded;
  load_for_sampling(a, c, loaded);
  std::string method_list;
  for (const std::string& m : config.methods) method_list += (method_list.empty() ? "" : ",") + m;
  if (with_q3) {
    method_list += ",q3-clusters";
    if (!loaded.map->has_visibility())
      throw Error(a.scene, 0, "the map has no visibility data: there are no q3map2 clusters to compare with");
    if (config.max_cells == 0) config.max_cells = 3 * static_cast<uint32_t>(loaded.map->cluster_count);
  }
  // On a map the view space is its non-solid space, for both samplers and the cells' weights.
  std::optional<Subdivision> map_bsp;
  if (loaded.map) {
    use_map_view_space(loaded, config.construction);
    config.evaluation.view_space = config.construction.view_space;
    config.evaluation.view_box = config.construction.view_box;
    if (!with_q3) {
      map_bsp = q3_subdivision(*loaded.map, config.construction.view_box);
      config.prepare = [&map_bsp](Subdivision& s) { weight_by_view_space(s, *map_bsp); };
    }
  }
  const uint32_t max_cells = config.max_cells;
  c.log("viewcells: comparing " + method_list + " up to " + std::to_string(max_cells) + " cells; " +
        std::to_string(config.construction.samples) + " construction samples (seed " +
        std::to_string(config.construction.seed) + "), " + std::to_string(config.evaluation.samples) +
        " evaluation samples (seed " + std::to_string(config.evaluation.seed) + "); view space " +
        loaded.view_space);
  std::optional<Q3Comparison> q3;
  Comparison plain;
  if (with_q3) q3 = compare_with_q3map2(loaded.scene, *loaded.map, *loaded.caster, config);
  else plain = compare_methods(loaded.scene, *loaded.caster, config);
  const Comparison& cmp = q3 ? q3->ours : plain;

  const MethodResult* avm = nullptr;
  for (const MethodResult& m : cmp.methods)
    if (m.method == "av-m") avm = &m;
  const std::vector<uint32_t> counts = report_cell_counts(max_cells);
  std::string csv = "method,cells,cost,ratio_to_av_m,constructed_cost\n";
  json methods = json::array();
  for (const MethodResult& m : cmp.methods) {
    // The report's counts, and where each method stopped (so that they compare there too).
    std::vector<uint32_t> at = counts;
    for (const MethodResult& other : cmp.methods) at.push_back(other.evaluated.cells.back());
    std::sort(at.begin(), at.end());
    at.erase(std::unique(at.begin(), at.end()), at.end());
    for (uint32_t n : at) {
      if (!has_point(m.evaluated, n)) continue;
      const double cost = m.evaluated.at(n);
      const std::string ratio = avm && has_point(avm->evaluated, n) ? fmt(cost / avm->evaluated.at(n), 6) : "";
      char line[256];
      std::snprintf(line, sizeof line, "%s,%u,%.6g,%s,%.6g\n", m.method.c_str(), n, cost, ratio.c_str(),
                    m.constructed.at(n));
      csv += line;
    }
    const uint32_t last = m.evaluated.cells.back();
    methods.push_back({{"method", m.method},
                       {"cells", m.leaves},
                       {"build_seconds", m.build_seconds},
                       {"stop_reason", m.stop_reason},
                       {"geometry_aligned", m.geometry_aligned},
                       {"axis_candidates_evaluated", m.axis_candidates},
                       {"geometry_candidates_evaluated", m.geometry_candidates},
                       {"evaluated_cost_at_most_cells", m.evaluated.at(last)},
                       {"constructed_cost_at_most_cells", m.constructed.at(last)}});
  }
  if (q3) {
    // q3map2's clusters: one point, at the map's cluster count.
    const uint32_t n = q3->cluster_count;
    const std::string ratio = avm && has_point(avm->evaluated, n) ? fmt(q3->clusters.cost / avm->evaluated.at(n), 6) : "";
    char line[256];
    std::snprintf(line, sizeof line, "q3-clusters,%u,%.6g,%s,\n", n, q3->clusters.cost, ratio.c_str());
    csv += line;
  }
  write_text_file(ca.output + "/curves.csv", csv);
  std::string hist = "method,cell,cost,volume\n";
  for (const MethodResult& m : cmp.methods)
    for (size_t i = 0; i < m.cells.size(); ++i) {
      char line[256];
      std::snprintf(line, sizeof line, "%s,%zu,%.6g,%.6g\n", m.method.c_str(), i, m.cells[i].cost, m.cells[i].volume);
      hist += line;
    }
  write_text_file(ca.output + "/histogram.csv", hist);
  json summary = {
      {"command", "compare"},
      {"scene", scene_summary(loaded.scene)},
      {"settings",
       {{"methods", config.methods},
        {"max_cells", ca.max_cells},
        {"construction_samples", config.construction.samples},
        {"construction_seed", config.construction.seed},
        {"evaluation_samples", config.evaluation.samples},
        {"evaluation_seed", config.evaluation.seed},
        {"histogram_cells", ca.histogram_cells ? ca.histogram_cells : max_cells},
        {"cost_model", {{"a", config.model.a}, {"b", config.model.b}, {"c", 0}}},
        {"axis_candidates", ca.axis_candidates},
        {"ga_candidates", ca.ga_candidates},
        {"geometry_aligned", ca.no_ga ? "off" : "auto"},
        {"robust_ray_casting", !a.fast},
        {"threads", threads.threads()}}},
      {"effects",
       {{"empty_space_detection",
         {{"enabled", cmp.construction.empty_space.enabled}, {"reason", cmp.construction.empty_space.reason}}},
        {"pixel_cost_term", {{"enabled", false}, {"reason", "c = 0: the comparison uses r(o) = max(a, b t)"}}}}},
      {"methods", methods},
      {"view_space", loaded.view_space},
      {"timings",
       {{"load_seconds", loaded.load_s},
        {"bvh_build_seconds", loaded.bvh_s},
        {"construction_sampling_seconds", cmp.construction.seconds},
        {"evaluation_sampling_seconds", cmp.evaluation.seconds},
        {"evaluation_seconds", cmp.evaluation_seconds}}}};
  if (q3) summary["q3map2"] = q3_report(*q3, loaded.scene, *loaded.map, ca.output, c);
  write_json(ca.output + "/summary.json", summary);
  for (const MethodResult& m : cmp.methods) {
    const uint32_t last = m.evaluated.cells.back();
    c.log("viewcells: " + m.method + ": " + std::to_string(m.leaves) + " cells in " + fmt(m.build_seconds, 2) +
          " s; evaluated cost " + fmt(m.evaluated.at(last), 1) + " at " + std::to_string(last) + " cells" +
          (avm && has_point(avm->evaluated, last) ? " (" + fmt(m.evaluated.at(last) / avm->evaluated.at(last), 3) + " x AV-M)"
                                                  : ""));
  }
  c.log("viewcells: curves -> " + ca.output + "/curves.csv, histograms -> " + ca.output +
        "/histogram.csv; plots: bash scripts/plot-compare.sh " + ca.output);
  return 0;
}

// -------------------------------------------------------------------------------- pvs

struct PvsArgs {
  std::string input, scene, output, report, method = "agvs", objects = "auto";
  uint32_t cells = 0;
  double pixel_error = 0, seconds = 0;
  uint64_t samples = 0, seed = 1;
  uint32_t batch = 20000;
  double min_share = 0.25;
  bool fast = false;
  uint32_t measure_cameras = 0;
  uint32_t measure_size = 1024;
  std::string save, resume, edited_from;
  std::vector<std::string> references;
  bool filter = false;
  double filter_k = 1.0;
  uint32_t filter_neighbours = 0;
};

int run_pvs(const PvsArgs& a, const Common& c);

// ---------------------------------------------------------------- extract, compress, query

/// "123", "64K", "2M", "1G" (powers of 1024) -> bytes.
uint64_t parse_bytes(const std::string& text) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  std::string unit = text.substr(used);
  double scale = 1;
  if (unit == "K" || unit == "k" || unit == "KB") scale = 1024.0;
  else if (unit == "M" || unit == "MB") scale = 1024.0 * 1024;
  else if (unit == "G" || unit == "GB") scale = 1024.0 * 1024 * 1024;
  else if (!unit.empty() && unit != "B") used = 0;
  if (used == 0 || !(v >= 0) || !std::isfinite(v * scale) || v * scale > 1e18)
    throw Error("--memory needs a size in bytes, e.g. 65536, 64K, 2M or 1G (got '" + text + "')");
  return static_cast<uint64_t>(v * scale);
}

struct CutArgs {
  uint32_t count = 0;
  std::string memory;
  double cost_ratio = 0;
};

void add_cut_options(CLI::App* app, CutArgs& a) {
  app->add_option("--count", a.count, "Exactly this many view cells")->check(whole(1, kMaxCells));
  app->add_option("--memory", a.memory,
                  "The most view cells whose approximate PVS storage fits this budget (bytes; K, M, G allowed)");
  app->add_option("--cost-ratio", a.cost_ratio,
                  "The fewest view cells whose render cost is within this ratio (>= 1) of the elementary cells'");
}

/// The view cells a cut rule asks for; `fallback_all` takes every elementary cell when no rule
/// is given (compress), else a rule is required (extract).
ViewCellSet choose_cells(const MergeHistory& h, const CutArgs& a, bool fallback_all) {
  const int rules = (a.count > 0) + !a.memory.empty() + (a.cost_ratio != 0);
  if (rules > 1) throw Error("give only one of --count, --memory and --cost-ratio");
  if (a.count > 0) return extract_by_count(h, a.count);
  if (!a.memory.empty()) return extract_by_memory(h, parse_bytes(a.memory));
  if (a.cost_ratio != 0) return extract_by_cost_ratio(h, a.cost_ratio);
  if (!fallback_all) throw Error("say which cells: --count N, --memory BYTES or --cost-ratio R");
  return extract_by_count(h, h.leaf_count);
}

SubdivisionFile read_merged(const std::string& path) {
  SubdivisionFile file = read_subdivision(path);
  if (!file.history)
    throw Error(path, 0, "no merge history in this file (it was built with --no-merge, or by an older version)");
  return file;
}

struct ExtractArgs {
  std::string input, output, mesh, png, scene;
  CutArgs cut;
  double slice_z = NAN;
  int width = 1024;
};

int run_extract(const ExtractArgs& e, const Common& c) {
  check_files({e.input, e.scene}, {e.output, e.mesh, e.png});

  SubdivisionFile file = read_merged(e.input);
  const MergeHistory& h = *file.history;
  const ViewCellSet set = choose_cells(h, e.cut, false);
  const std::vector<int32_t> leaves = file.subdivision.leaves();
  c.log("viewcells: " + std::to_string(set.cells.size()) + " view cells (" + set.rule + "), render cost " +
        fmt(set.cost, 1) + " (elementary cells: " + fmt(h.initial_cost, 1) + "), approximate PVS " +
        std::to_string(set.pvs_bytes) + " bytes");
  json cells = json::array();
  for (size_t i = 0; i < set.cells.size(); ++i) {
    const MergeNode& n = h.nodes[set.cells[i]];
    json bsp_leaves = json::array();
    for (uint32_t l : h.leaves_under(set.cells[i])) bsp_leaves.push_back(leaves[l]);
    cells.push_back({{"id", i},
                     {"merge_node", set.cells[i]},
                     {"bsp_leaves", bsp_leaves},
                     {"volume", n.volume},
                     {"bounds", {{"min", {n.bounds.lo.x, n.bounds.lo.y, n.bounds.lo.z}},
                                 {"max", {n.bounds.hi.x, n.bounds.hi.y, n.bounds.hi.z}}}},
                     {"pvs_size", n.pvs_size},
                     {"pvs_cost", n.pvs_cost}});
  }
  json out = {{"command", "extract"},
              {"input", e.input},
              {"rule", set.rule},
              {"cells", set.cells.size()},
              {"cost", set.cost},
              {"cost_of_elementary_cells", h.initial_cost},
              {"cost_ratio", set.cost / h.initial_cost},
              {"pvs_entries", set.pvs_entries},
              {"approximate_pvs_bytes", set.pvs_bytes},
              {"view_cells", cells}};
  if (!e.output.empty()) {
    write_json(e.output, out);
    c.log("viewcells: view cells -> " + e.output);
  }
  if (!e.mesh.empty() || !e.png.empty()) {
    rebuild_cells(file.subdivision);
    const CellView view = merged_cell_view(file.subdivision, h, set.cells);
    std::unique_ptr<Scene> scene;
    if (!e.scene.empty()) scene = std::make_unique<Scene>(load_scene(e.scene));
    write_views(file.subdivision, scene.get(), e.mesh, e.png, e.slice_z, e.width, c, &view);
  }
  if (e.output.empty() && e.mesh.empty() && e.png.empty()) std::cout << out.dump(2) << '\n';
  return 0;
}

struct CompressArgs {
  std::string input, output, flat, report;
  CutArgs cut;
};

/// The .pvs file of the view cells `set` of a built hierarchy (PVSs: the sampled ones).
PvsFile pvs_file_for(const SubdivisionFile& file, const ViewCellSet& set) {
  PvsFile pf = make_pvs_file(file.subdivision, file.leaf_pvs, *file.history, set.cells);
  pf.object_count = file.object_count;
  pf.object_names = file.object_names;
  pf.scene_fingerprint = file.scene_fingerprint;
  pf.rule = set.rule;
  return pf;
}

/// Writes the .pvs file, then reads it back: every cell's PVS must come back as `lists`.
void write_pvs_checked(const std::string& path, const PvsFile& pf, const std::vector<std::vector<uint32_t>>& lists) {
  write_pvs(path, pf);
  const PvsFile back = read_pvs(staged_path(path));  // the command's outputs are renamed at its end
  for (uint32_t i = 0; i < back.pvs.cell_count; ++i)
    if (back.pvs.cell_pvs(i) != lists[i]) throw Error(path, 0, "read-back check failed for cell " + std::to_string(i));
}

/// NaN (not known) as JSON null.
json number_or_null(double v) { return std::isnan(v) ? json(nullptr) : json(v); }

int run_pvs(const PvsArgs& a, const Common& c) {
  {
    // --save may be the --resume state (continue and keep it up to date); nothing else may meet.
    std::error_code ec;
    const bool save_is_resume = !a.save.empty() && !a.resume.empty() &&
                                (a.save == a.resume || std::filesystem::equivalent(a.save, a.resume, ec));
    std::vector<std::string> inputs = {a.input, a.scene, a.edited_from, save_is_resume ? "" : a.resume};
    inputs.insert(inputs.end(), a.references.begin(), a.references.end());
    check_files(inputs, {a.output, a.report, a.save});
  }
  ThreadLimit threads(c.threads);
  AgvsConfig config;
  config.method = parse_agvs_method(a.method);
  config.seed = a.seed;
  config.batch_size = a.batch;
  config.min_share = a.min_share;
  config.max_samples = a.samples;
  config.max_seconds = a.seconds;
  config.pixel_error = a.pixel_error;
  config.show_progress = !c.quiet;
  if (!a.samples && !(a.seconds > 0) && !(a.pixel_error > 0))
    throw Error("give when to stop: --pixel-error, --time or --samples");
  config.filter_statistics = a.filter || a.filter_neighbours > 0;
  if (!(a.filter_k >= 0) || !std::isfinite(a.filter_k)) throw Error("--filter-k must be a finite number >= 0");
  if (a.filter_k != 1.0 && !a.filter) throw Error("--filter-k sets the object space filter's factor: add --filter");
  if (!a.edited_from.empty() && a.resume.empty())
    throw Error("--edited-from needs --resume: the state computed on that scene, to carry over to --scene");
  SubdivisionFile file = read_merged(a.input);
  const MergeHistory& h = *file.history;
  CutArgs cut;
  cut.count = a.cells;
  const ViewCellSet set = choose_cells(h, cut, true);
  Stopwatch sw;
  const ObjectGrouping grouping = parse_grouping(a.objects);
  const Scene scene = load_scene(a.scene, grouping);
  // Dynamic edits: the hierarchy and the state belong to the scene before the edit.
  std::optional<Scene> before;
  if (!a.edited_from.empty()) {
    before.emplace(load_scene(a.edited_from, grouping));
    if (before->fingerprint() != file.scene_fingerprint)
      throw Error(a.edited_from, 0, "is not the scene " + a.input + " was built from (fingerprints differ)");
  } else if (scene.fingerprint() != file.scene_fingerprint) {
    throw Error(a.scene, 0,
                "is not the scene " + a.input + " was built from (fingerprints differ; after editing the scene, "
                "give the original with --edited-from)");
  }
  EmbreeConfig ec;
  ec.robust = !a.fast;
  const auto caster = make_embree_caster(scene, ec);
  PvsFile pf = pvs_file_for(file, set);
  pf.rule += "; PVS by " + a.method;
  // The PVSs name the objects of the scene sampled (the edited one, after an edit).
  pf.object_count = static_cast<uint32_t>(scene.object_count());
  pf.object_names.clear();
  for (const ObjectInfo& o : scene.objects) pf.object_names.push_back(o.name);
  pf.scene_fingerprint = scene.fingerprint();
  const CellLocator cells(pf.bsp, pf.leaf_cell, pf.pvs.cell_count);
  const double setup_s = sw.seconds();
  c.log("viewcells: " + std::to_string(cells.cell_count()) + " view cells (" + set.rule + "), PVS by " + a.method +
        " until " +
        (a.pixel_error > 0 ? "an estimated pixel error of " + fmt(a.pixel_error, 2) + " "
                           : std::string()) +
        (a.seconds > 0 ? fmt(a.seconds, 1) + " s " : std::string()) +
        (a.samples ? std::to_string(a.samples) + " samples" : std::string()));
  // A saved state belongs to a scene and these view cells.
  auto identity_of = [&](uint64_t scene_fingerprint) {
    ByteWriter cells_id;
    cells_id.put(scene_fingerprint);
    cells_id.put_array(pf.leaf_cell);
    cells_id.put_array(pf.cell_mht_node);
    return fnv1a64(cells_id.data());
  };
  const uint64_t identity = identity_of(scene.fingerprint());
  std::unique_ptr<RayCaster> caster_before;
  std::optional<AgvsSolver> solver;
  std::optional<AgvsEditStats> edit;
  if (before && AgvsSolver::state_identity(a.resume) != identity) {
    // The state describes the scene before the edit: load it there, then edit.
    caster_before = make_embree_caster(*before, ec);
    solver.emplace(*before, *caster_before, cells, config);
    solver->load(a.resume, identity_of(before->fingerprint()));
    c.log("viewcells: resumed from " + a.resume + " after " + std::to_string(solver->stats().samples) +
          " samples on " + a.edited_from);
    edit = solver->edit(scene, *caster, match_objects(*before, scene));
    c.log("viewcells: edit: " + std::to_string(edit->deleted) + " objects deleted (" +
          std::to_string(edit->removed_deleted) + " PVS entries), " + std::to_string(edit->inserted) +
          " inserted (" + std::to_string(edit->removed_penumbra) + " entries in their penumbrae removed, " +
          std::to_string(edit->cells_cleared) + " cells they touch emptied)");
  } else {
    solver.emplace(scene, *caster, cells, config);
    if (!a.resume.empty()) {
      solver->load(a.resume, identity);
      c.log("viewcells: resumed from " + a.resume + " after " + std::to_string(solver->stats().samples) +
            " samples");
    }
  }
  for (const std::string& path : a.references) {
    const PvsFile ref = read_pvs(path);
    if (ref.pvs.cell_count != cells.cell_count() || ref.object_count != pf.object_count ||
        ref.scene_fingerprint != pf.scene_fingerprint || ref.leaf_cell != pf.leaf_cell)
      throw Error(path, 0, "is not a .pvs of these view cells of this scene");
    std::vector<std::vector<uint32_t>> ref_lists(ref.pvs.cell_count);
    for (uint32_t i = 0; i < ref.pvs.cell_count; ++i) ref_lists[i] = ref.pvs.cell_pvs(i);
    solver->add_reference(GlobalPvs::from_lists(pf.object_count, ref_lists));
  }
  solver->run();
  if (!a.save.empty()) {
    solver->save(a.save, identity);
    c.log("viewcells: state -> " + a.save + " (continue with --resume)");
  }
  const AgvsStats& st = solver->stats();
  // The sampled PVSs (filtered, when asked) replace the construction ones, compressed through
  // the hierarchy.
  const bool filtering = config.filter_statistics;
  VisibilityFilter filter;
  filter.object_space = a.filter;
  filter.k = a.filter_k;
  filter.view_neighbours = a.filter_neighbours;
  std::vector<std::vector<uint32_t>> lists(cells.cell_count());
  if (filtering) {
    lists = solver->filtered_pvs(filter);
  } else {
    for (uint32_t i = 0; i < cells.cell_count(); ++i) lists[i] = solver->pvs().list(i);
  }
  const GlobalPvs written = GlobalPvs::from_lists(pf.object_count, lists);
  const double mean_written = static_cast<double>(written.entries()) / cells.cell_count();
  if (filtering)
    c.log("viewcells: visibility filter (" + std::string(a.filter ? "object space, k = " + fmt(a.filter_k, 2) : "") +
          (a.filter && a.filter_neighbours ? ", " : "") +
          (a.filter_neighbours ? "view space, " + std::to_string(a.filter_neighbours) + " neighbours" : "") +
          "): mean PVS " + fmt(solver->mean_pvs(), 1) + " -> " + fmt(mean_written, 1) + " objects");
  pf.pvs = compress_pvs(h, set.cells, lists);
  write_pvs_checked(a.output, pf, lists);
  const double err = solver->pixel_error(), bound = solver->pixel_error_bound();
  std::optional<PixelErrorMeasure> measured, measured_unfiltered;
  if (a.measure_cameras) {
    Stopwatch ms;
    auto measure = [&](const GlobalPvs& pvs) {
      return measure_pixel_error(scene, *caster, cells, pvs, a.measure_cameras, a.measure_size, a.measure_size, 90.0,
                                 a.seed + 17, st.empty_space.enabled, config.resolution);
    };
    measured = measure(written);
    if (filtering) measured_unfiltered = measure(solver->pvs());
    c.log("viewcells: measured pixel error " + fmt(measured->pixels, 2) +
          (filtering ? " (unfiltered " + fmt(measured_unfiltered->pixels, 2) + ")" : std::string()) + " of " +
          std::to_string(config.resolution) + " pixels (" + std::to_string(measured->cameras) + " cameras of " +
          std::to_string(a.measure_size) + "x" + std::to_string(a.measure_size) + ", " + fmt(ms.seconds(), 1) +
          " s)");
  }
  auto measure_json = [&](const std::optional<PixelErrorMeasure>& m) {
    return m ? json{{"pixels", m->pixels}, {"share", m->share}, {"cameras", m->cameras},
                    {"cameras_with_wrong_pixels", m->cameras_wrong},
                    {"camera_size", a.measure_size}, {"fov_degrees", 90}}
             : json(nullptr);
  };
  c.log("viewcells: " + std::to_string(st.samples) + " samples (" + std::to_string(st.rays) + " rays) in " +
        fmt(st.seconds, 2) + " s; mean PVS " + fmt(solver->mean_pvs(), 1) + " objects; estimated pixel error " +
        (!std::isnan(err)     ? fmt(err, 2)
         : !std::isnan(bound) ? "below " + fmt(bound, 2) + " (90% bound: too few wrong camera rays for an estimate)"
                              : std::string("not yet known")) + " (" + st.stop_reason + "); -> " + a.output);
  if (!a.report.empty()) {
    json dists = json::array();
    for (int d = 0; d < AgvsStats::kDistributions; ++d)
      dists.push_back({{"distribution", to_string(static_cast<AgvsDistribution>(d))},
                       {"samples", st.dist_samples[d]},
                       {"rays", st.dist_rays[d]},
                       {"contribution", st.dist_contribution[d]},
                       {"last_probability", st.dist_probability[d]}});
    json curve = json::array();
    for (const AgvsPoint& p : st.curve)
      curve.push_back({{"seconds", p.seconds}, {"samples", p.samples}, {"rays", p.rays}, {"mean_pvs_size", p.mean_pvs},
                       {"pixel_error", number_or_null(p.pixel_error)},
                       {"pixel_error_bound", number_or_null(p.pixel_error_bound)},
                       {"camera_rays", p.camera_rays},
                       {"wrong_camera_rays", p.wrong_camera_rays},
                       {"covered", json(std::vector<uint64_t>(p.covered, p.covered + a.references.size()))}});
    const json report = {
        {"command", "pvs"},
        {"input", a.input},
        {"scene", a.scene},
        {"output", a.output},
        {"method", a.method},
        {"cells", cells.cell_count()},
        {"rule", set.rule},
        {"settings",
         {{"seed", a.seed}, {"batch_size", a.batch}, {"resolution", config.resolution}, {"threads", threads.threads()},
          {"window_p", config.window_p}, {"window_k", config.window_k}}},
        {"effects",
         {{"empty_space_detection", {{"enabled", st.empty_space.enabled}, {"reason", st.empty_space.reason}}},
          {"silhouette_mutation",
           {{"enabled", config.method == AgvsMethod::kAgvs},
            {"reason", config.method == AgvsMethod::kAgvs ? "part of the AGVS mixture" : "AGVS only"}}},
          {"visibility_filter",
           {{"enabled", filtering},
            {"reason", filtering ? "asked for (--filter / --filter-neighbours): the written PVSs are extended by "
                                   "objects likely visible given the sampling density"
                                 : "not asked for: the written PVSs are the sampled ones"}}}}},
        {"filter", filtering ? json{{"object_space", a.filter},
                                    {"k", a.filter_k},
                                    {"view_neighbours", a.filter_neighbours},
                                    {"mean_pvs_size_unfiltered", solver->mean_pvs()},
                                    {"mean_pvs_size_filtered", mean_written},
                                    {"measured_pixel_error_unfiltered", measure_json(measured_unfiltered)}}
                             : json(nullptr)},
        {"edit", edit ? json{{"edited_from", a.edited_from},
                             {"deleted_objects", edit->deleted},
                             {"inserted_objects", edit->inserted},
                             {"entries_of_deleted_objects", edit->removed_deleted},
                             {"entries_in_penumbrae", edit->removed_penumbra},
                             {"cells_emptied", edit->cells_cleared}}
                      : json(nullptr)},
        {"samples", st.samples},
        {"rays", st.rays},
        {"seconds", st.seconds},
        {"setup_seconds", setup_s},
        {"samples_per_second", st.seconds > 0 ? st.samples / st.seconds : 0.0},
        {"mean_pvs_size", solver->mean_pvs()},
        {"mean_pvs_size_written", mean_written},
        {"pvs_entries", solver->pvs().entries()},
        {"estimated_pixel_error", number_or_null(err)},
        {"pixel_error_bound", number_or_null(bound)},
        {"estimator_window_rays", st.window_rays},
        {"measured_pixel_error", measure_json(measured)},
        {"stop_reason", st.stop_reason},
        {"distributions", dists},
        {"curve", curve}};
    write_json(a.report, report);
    c.log("viewcells: report -> " + a.report);
  }
  return 0;
}

int run_compress(const CompressArgs& a, const Common& c) {
  check_files({a.input}, {a.output, a.flat, a.report});

  SubdivisionFile file = read_merged(a.input);
  const MergeHistory& h = *file.history;
  const ViewCellSet set = choose_cells(h, a.cut, true);
  Stopwatch sw;
  PvsFile pf = pvs_file_for(file, set);
  const double compress_s = sw.seconds();
  // Sizes before (every cell lists its whole PVS) and after (each node keeps its part).
  std::vector<std::vector<uint32_t>> flat(pf.pvs.cell_count);
  uint64_t before = 0;
  for (uint32_t i = 0; i < pf.pvs.cell_count; ++i) {
    flat[i] = pf.pvs.cell_pvs(i);
    before += flat[i].size();
  }
  const uint64_t after = pf.pvs.stored_entries();
  const uint64_t varint_before = varint_bytes(flat), varint_after = varint_bytes(pf.pvs.stored);
  write_pvs_checked(a.output, pf, flat);
  const uint64_t file_bytes = std::filesystem::file_size(staged_path(a.output));
  c.log("viewcells: " + std::to_string(pf.pvs.cell_count) + " view cells (" + set.rule + "): " +
        std::to_string(before) + " PVS entries -> " + std::to_string(after) + " kept in " +
        std::to_string(pf.pvs.node_count()) + " hierarchy nodes (" + fmt(before ? double(after) / before : 1.0, 3) +
        "); " + a.output + ": " + std::to_string(file_bytes) + " bytes");
  json report = {{"command", "compress"},
                 {"input", a.input},
                 {"output", a.output},
                 {"rule", set.rule},
                 {"cells", pf.pvs.cell_count},
                 {"objects", pf.object_count},
                 {"hierarchy_nodes", pf.pvs.node_count()},
                 {"entries_before", before},
                 {"entries_after", after},
                 {"entry_ratio", before ? double(after) / before : 1.0},
                 {"raw_bytes_before", 4 * before},
                 {"raw_bytes_after", 4 * after},
                 {"varint_bytes_before", varint_before},
                 {"varint_bytes_after", varint_after},
                 {"file_bytes", file_bytes},
                 {"seconds", compress_s}};
  if (!a.flat.empty()) {
    const uint64_t rle = write_flat_rows(a.flat, pf);
    const uint64_t rows = static_cast<uint64_t>(pf.pvs.cell_count) * ((pf.object_count + 7) / 8);
    report["flat"] = {{"file", a.flat}, {"bit_row_bytes", rows}, {"run_length_bytes", rle},
                      {"file_bytes", std::filesystem::file_size(staged_path(a.flat))}};
    c.log("viewcells: flat rows -> " + a.flat + ": " + std::to_string(rows) + " bytes of bit rows, " +
          std::to_string(rle) + " run-length coded (Quake style)");
  }
  if (!a.report.empty()) {
    write_json(a.report, report);
    c.log("viewcells: report -> " + a.report);
  }
  return 0;
}

struct QueryArgs {
  std::string input;
  std::vector<double> point;
  bool json_out = false;
};

int run_query(const QueryArgs& q, const Common&) {
  const PvsFile f = read_pvs(q.input);
  if (q.point.size() != 3) throw Error("query needs a point: X Y Z");
  const Vec3 p{q.point[0], q.point[1], q.point[2]};
  if (!is_finite(p)) throw Error("query point has non-finite coordinates");
  const int32_t cell = f.locate(p);
  if (cell < 0)
    throw Error("(" + fmt(p.x, 3) + ", " + fmt(p.y, 3) + ", " + fmt(p.z, 3) + ") is outside the view space");
  const std::vector<uint32_t> pvs = f.pvs.cell_pvs(static_cast<uint32_t>(cell));
  auto name = [&](uint32_t o) { return f.object_names.empty() ? std::string() : f.object_names[o]; };
  if (q.json_out) {
    json objects = json::array();
    for (uint32_t o : pvs) objects.push_back({{"id", o}, {"name", name(o)}});
    std::cout << json{{"point", {p.x, p.y, p.z}},
                      {"cell", cell},
                      {"cells", f.pvs.cell_count},
                      {"merge_node", f.cell_mht_node[cell]},
                      {"pvs", objects}}
                     .dump(2)
              << '\n';
    return 0;
  }
  std::cout << "cell " << cell << " of " << f.pvs.cell_count << " (" << f.rule << "): " << pvs.size() << " of "
            << f.object_count << " objects visible\n";
  for (uint32_t o : pvs) std::cout << "  " << o << (f.object_names.empty() ? "" : "  " + name(o)) << '\n';
  return 0;
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{
      "viewcells: builds view cells for visibility preprocessing from the visibility of the scene itself.\n"
      "Pipeline: generate or load a scene -> sample visibility segments -> subdivide the view space\n"
      "into cells and merge them into a hierarchy (build) -> cut view cells from it (extract) ->\n"
      "write their compressed PVS (compress) -> look a viewpoint up (query)."};
  app.require_subcommand(1);
  app.fallthrough();
  Common common;
  app.add_option("--threads", common.threads, "Worker threads (0 = all cores); results do not depend on it")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", common.quiet, "No progress bars or log lines on stderr");
  std::string isa;
  app.add_option("--embree-isa", isa,
                 "Embree's instruction set: sse2, sse4.2, avx, avx2 or avx512 (default: VIEWCELLS_EMBREE_ISA, else "
                 "the CPU's best). Sampled results are bit-identical across machines only for the same ISA; reports "
                 "and file headers record it");

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
  SampleOnlyArgs smp_out;
  auto* s = app.add_subcommand("sample", "Cast visibility segments through the view space (paper section 4.1)");
  add_sampling_options(s, smp);
  s->add_option("-o,--output", smp_out.output, "Segment file to write (.vseg)");
  s->add_option("--report", smp_out.report, "JSON report: settings, effects enabled and why, counts, timings");
  s->add_flag("--measure-raw", smp_out.measure_raw,
              "Also cast the same rays (re-casts included) through Embree alone; report raw_rays_per_second");

  SampleArgs bsmp;
  BuildArgs bld;
  auto* bc = app.add_subcommand("build", "Sample visibility and subdivide the view space into cells (AV-S, section 4.2)");
  add_sampling_options(bc, bsmp);
  bc->add_option("--max-cells", bld.max_cells, "Stop at this many cells")->capture_default_str()->check(whole(1, kMaxCells));
  auto* no_ga = bc->add_flag("--no-ga", bld.no_ga, "No geometry-aligned split candidates");
  bc->add_flag("--ga", bld.ga, "Geometry-aligned candidates even for mostly axis-aligned scenes")->excludes(no_ga);
  bc->add_option("--ga-candidates", bld.ga_candidates, "Geometry-aligned planes tried per cell at most")
      ->capture_default_str();
  bc->add_option("--axis-candidates", bld.axis_candidates, "Axis-aligned positions tried per axis and cell at most")
      ->capture_default_str()->check(CLI::PositiveNumber);
  bc->add_option("--min-reduction", bld.min_reduction,
                 "Stop when splits reduce the cost by less than this share of the initial cost for 50 splits running")
      ->capture_default_str();
  bc->add_option("--cost-a", bld.cost_a, "Render cost model: minimum cost of an object (r = max(a, b * triangles))")
      ->capture_default_str();
  bc->add_option("--cost-b", bld.cost_b, "Render cost model: cost per triangle")->capture_default_str();
  bc->add_option("--cost-c", bld.cost_c,
                 "Render cost model: cost per projected pixel, estimated per cell from its corners and centre "
                 "(0: no pixel term, nothing estimated)")
      ->capture_default_str();
  bc->add_option("--screen", bld.screen, "Screen WIDTHxHEIGHT the pixel term assumes (with --cost-c)")
      ->capture_default_str();
  bc->add_option("--fov", bld.fov, "Horizontal field of view in degrees the pixel term assumes (with --cost-c)")
      ->capture_default_str();
  bc->add_option("--density-band", bld.density_band,
                 "Viewpoint density zlo,zhi[,outside]: weight 1 between the heights, outside (default 0.1) elsewhere");
  bc->add_flag("--no-merge", bld.no_merge, "Keep the AV-S cells: no merge history (extract and compress need one)");
  bc->add_option("-o,--output", bld.output, "Hierarchy file to write (.vcells)");
  bc->add_option("--report", bld.report, "JSON report: settings, effects and why, costs, candidates, timings");
  bc->add_option("--mesh", bld.mesh, "Also write the cells as a PLY coloured by render cost");
  bc->add_option("--slice-png", bld.slice_png, "Also write a PNG of a horizontal slice through the cells");
  bc->add_option("--slice-z", bld.slice_z, "Height of the slice (default: middle of the view space)");
  bc->add_option("--slice-width", bld.slice_width, "Slice image width in pixels")->capture_default_str()->check(whole(16, 16384));

  ExportArgs exp;
  auto* ex = app.add_subcommand("export", "Look at a built hierarchy: cells as PLY, or a slice as PNG");
  ex->add_option("cells", exp.input, "Hierarchy file (.vcells)")->required();
  ex->add_option("--mesh", exp.mesh, "PLY of the cells, coloured by render cost");
  ex->add_option("--slice-png", exp.png, "PNG of a horizontal slice");
  ex->add_option("--slice-z", exp.slice_z, "Height of the slice (default: middle of the view space)");
  ex->add_option("--slice-width", exp.width, "Slice image width in pixels")->capture_default_str()->check(whole(16, 16384));
  ex->add_option("--scene", exp.scene, "Draw this scene's cross-section into the slice");

  SampleArgs csmp;
  CompareArgs cmpa;
  auto* cm = app.add_subcommand("compare",
                                "Build view cells with several methods from the same samples and score them all on "
                                "independent evaluation samples (paper, section 6)");
  add_sampling_options(cm, csmp);
  cm->add_option("--methods", cmpa.methods,
                 "Comma-separated: av-m, av-s, kd-casm, kd-lasm, kd-vt, kd-vt-star, bsp, and q3-clusters (the clusters "
                 "q3map2 compiled into a Quake 3 map; the default on a .bsp with visibility data, with av-m,av-s,kd-casm)")
      ->capture_default_str()
      ->each([&](const std::string&) { cmpa.methods_given = true; });
  cm->add_option("--max-cells", cmpa.max_cells, "Cells per method at most (on a Quake 3 map: 3 x its clusters)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->each([&](const std::string&) { cmpa.max_cells_given = true; });
  cm->add_option("--eval-samples", cmpa.eval_samples, "Evaluation samples (default: 4 x --samples)")
      ->check(whole(1, kMaxSamples));
  cm->add_option("--eval-seed", cmpa.eval_seed, "Evaluation seed (default: --seed + 1000003)");
  cm->add_option("--histogram-cells", cmpa.histogram_cells, "Cell count of the cost histograms (default: --max-cells)");
  cm->add_option("--cost-a", cmpa.cost_a, "Render cost model: minimum cost of an object")->capture_default_str();
  cm->add_option("--cost-b", cmpa.cost_b, "Render cost model: cost per triangle")->capture_default_str();
  cm->add_flag("--no-ga", cmpa.no_ga, "AV-S/AV-M without geometry-aligned candidates");
  cm->add_option("--axis-candidates", cmpa.axis_candidates, "AV-S/AV-M: axis-aligned positions per axis and cell")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cm->add_option("--ga-candidates", cmpa.ga_candidates, "AV-S/AV-M: geometry-aligned planes per cell")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cm->add_option("-o,--output", cmpa.output, "Directory for curves.csv, histogram.csv, summary.json")->required();

  ExtractArgs ext;
  auto* xt = app.add_subcommand("extract", "Cut view cells from the merge history of a built hierarchy");
  xt->add_option("cells", ext.input, "Hierarchy file (.vcells, built with merging)")->required();
  add_cut_options(xt, ext.cut);
  xt->add_option("-o,--output", ext.output, "JSON file of the view cells (default: printed)");
  xt->add_option("--mesh", ext.mesh, "PLY of the BSP leaves coloured by their view cell's render cost");
  xt->add_option("--slice-png", ext.png, "PNG of a horizontal slice, borders between view cells");
  xt->add_option("--slice-z", ext.slice_z, "Height of the slice (default: middle of the view space)");
  xt->add_option("--slice-width", ext.width, "Slice image width in pixels")->capture_default_str()->check(whole(16, 16384));
  xt->add_option("--scene", ext.scene, "Draw this scene's cross-section into the slice");

  CompressArgs cmp;
  auto* cp = app.add_subcommand("compress",
                                "Write the view cells' PVSs, compressed through the hierarchy, as a .pvs file");
  cp->add_option("cells", cmp.input, "Hierarchy file (.vcells, built with merging)")->required();
  add_cut_options(cp, cmp.cut);
  cp->add_option("-o,--output", cmp.output, "The .pvs file to write")->required();
  cp->add_option("--flat", cmp.flat, "Also write Quake-style run-length coded bit rows, to compare sizes");
  cp->add_option("--report", cmp.report, "JSON report: entries and bytes before and after");

  PvsArgs pva;
  auto* pv = app.add_subcommand("pvs",
                                "Compute the view cells' PVSs by adaptive global visibility sampling (AGVS) and write "
                                "them, compressed, as a .pvs file");
  pv->add_option("cells", pva.input, "Hierarchy file (.vcells, built with merging)")->required();
  pv->add_option("--scene", pva.scene, "The scene the hierarchy was built from")->required();
  pv->add_option("--objects", pva.objects, "Object grouping used when building")->capture_default_str();
  pv->add_option("--cells", pva.cells, "View cells cut from the merge history (default: every elementary cell)")
      ->check(whole(1, kMaxCells));
  pv->add_option("--pixel-error", pva.pixel_error,
                 "Stop when the estimated pixel error (pixels of a 1024x1024 image that differ) is at most this")
      ->check(positive());
  pv->add_option("--time", pva.seconds, "Stop after this many seconds")->check(positive());
  pv->add_option("--samples", pva.samples,
                 "Stop after this many samples (checked between batches: a run may pass it by less than a batch)")
      ->check(whole(1, kMaxSamples));
  pv->add_option("--method", pva.method, "agvs (adaptive mixture), sgvs (view space-direction only) or ref (per cell)")
      ->capture_default_str();
  pv->add_option("--seed", pva.seed, "Random seed")->capture_default_str();
  pv->add_option("--batch", pva.batch, "Samples per batch")->capture_default_str()->check(whole(1, 100'000'000));
  pv->add_flag("--fast", pva.fast, "Embree without robust mode");
  pv->add_option("--min-share", pva.min_share,
                 "AGVS: share of every batch kept for view space-direction samples whatever their weight; they are "
                 "the pixel error estimator's camera rays (more: a finer estimate, fewer samples for the mutations)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  pv->add_option("--measure-cameras", pva.measure_cameras,
                 "Also measure the pixel error: render this many random cameras by ray casting and count the "
                 "pixels whose object is missing from the PVS")
      ->check(whole(1, 1'000'000));
  pv->add_option("--save", pva.save, "Write the solver's state here at the end, to continue later with --resume");
  pv->add_option("--resume", pva.resume,
                 "Continue from a state written by --save (same scene, cells, method, seed and batch); --samples "
                 "and --time count from the start of the computation, the saved part included");
  pv->add_flag("--filter", pva.filter,
              "Write PVSs extended by the object space visibility filter: objects near the PVS's objects, within "
              "a distance that shrinks as the sampling gets denser (sampling itself goes on unfiltered)");
  pv->add_option("--filter-k", pva.filter_k, "The filter's factor k: larger is more conservative")
      ->capture_default_str();
  pv->add_option("--filter-neighbours", pva.filter_neighbours,
                 "View space filter: merge each cell's PVS with those of this many neighbouring cells with the most "
                 "similar PVSs");
  pv->add_option("--edited-from", pva.edited_from,
                 "Dynamic edit: --scene is an edited version of this scene (the one the hierarchy and the --resume "
                 "state were computed on). Objects are matched by name and geometry; deleted ones leave the PVSs, "
                 "and what inserted ones may hide is removed before sampling resumes");
  pv->add_option("--reference", pva.references,
                 "A .pvs of the same cells (another method's result; up to 2): the report's curve counts the "
                 "entries found so far that it has too")
      ->expected(1, AgvsPoint::kReferences)
      ->check(CLI::ExistingFile);
  pv->add_option("--measure-size", pva.measure_size, "Width and height of the measuring cameras, in pixels")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  pv->add_option("-o,--output", pva.output, "The .pvs file to write")->required();
  pv->add_option("--report", pva.report, "JSON report: samples, rays, mean PVS size, estimated pixel error, curve");

  bool isa_supported = false;
  auto* is = app.add_subcommand("isa", "Print the Embree ISA that ray casting would use (see --embree-isa)");
  is->add_flag("--supported", isa_supported, "Print every ISA this CPU runs instead, one per line, best last");

  QueryArgs qry;
  auto* qy = app.add_subcommand("query", "Print the view cell containing a point and its PVS");
  qy->add_option("pvs", qry.input, "A .pvs file (from compress)")->required();
  qy->add_option("point", qry.point, "X Y Z")->required()->expected(3);
  qy->add_flag("--json", qry.json_out, "Print JSON");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::cerr << "viewcells: error: " << e.what() << "\nRun with --help for more information.\n";
    return e.get_exit_code();
  }
  auto run_command = [&]() -> int {
    if (*g) return run_generate(gen, common);
    if (*i) return run_info(info, common);
    if (*s) {
      smp.segments_given = s->count("--segments") > 0;
      return run_sample(smp, smp_out, common);
    }
    if (*bc) {
      bsmp.segments_given = bc->count("--segments") > 0;
      return run_build(bsmp, bld, common);
    }
    if (*ex) return run_export(exp, common);
    if (*xt) return run_extract(ext, common);
    if (*cm) {
      csmp.segments_given = cm->count("--segments") > 0;
      return run_compare(csmp, cmpa, common);
    }
    if (*cp) return run_compress(cmp, common);
    if (*pv) return run_pvs(pva, common);
    if (*qy) return run_query(qry, common);
    if (*is) {
      if (isa_supported) {
        for (const std::string& name : supported_embree_isas()) std::cout << name << '\n';
      } else {
        std::cout << embree_isa() << '\n';
      }
      return 0;
    }
    return 0;
  };
  try {
    // One setting for the whole process, read by every caster and file header (core/isa.h).
    if (!isa.empty()) setenv("VIEWCELLS_EMBREE_ISA", checked_embree_isa(isa).c_str(), 1);
    embree_isa();  // a bad VIEWCELLS_EMBREE_ISA fails here, before any work
    // Every file a command writes is renamed into place only when the whole command succeeded.
    OutputBatch outputs;
    const int rc = run_command();
    if (rc == 0) outputs.commit();
    return rc;
  } catch (const Error& e) {
    std::cerr << "viewcells: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "viewcells: error: " << e.what() << '\n';
    return 2;
  }
}

}  // namespace viewcells::cli
