// generate, info, sample, isa: scenes and the rays through them.
#include <iostream>

#include "options.h"
#include "viewcells/q3/level.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pipeline/play.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/scene/generators.h"
#include "viewcells/vis/level_view.h"

namespace viewcells::cli {

namespace {

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

struct ConvertArgs {
  std::string scene, output;
  std::string objects = "auto";
  double metres_per_unit = 0;
  bool start_points = false;
};

int run_convert(const ConvertArgs& a, const Common& c) {
  check_files({a.scene}, {a.output});
  if (lower_extension(a.output) != ".glb") throw Error(a.output, 0, "convert writes binary glTF: give a .glb output");
  Stopwatch sw;
  const Scene scene = load_scene(a.scene, parse_grouping(a.objects));
  const bool map = is_q3_map(a.scene);
  SceneGltfOptions options;
  options.metres_per_unit = a.metres_per_unit > 0 ? a.metres_per_unit
                            : scene.metres_per_unit > 0 ? scene.metres_per_unit : 1.0;
  if (a.start_points) options.start_points = map ? q3_spawn_points(read_q3bsp(a.scene)) : scene.start_points;
  if (map) {
    // The map's sky is drawn (with a sky shader) and closes the level: it is written as meshes;
    // the solid brushes that close the map for rays are not surfaces, and are left behind.
    for (const ObjectInfo& o : scene.objects) options.keep.push_back(o.name != "solid brushes");
  }
  write_scene_gltf(a.output, scene, options);
  size_t written = 0;
  for (size_t o = 0; o < scene.object_count(); ++o)
    written += options.keep.empty() ? scene.objects[o].rendered : options.keep[o];
  c.log("viewcells: " + a.scene + " -> " + a.output + ": " + std::to_string(written) + " objects of " +
        std::to_string(scene.object_count()) + ", 1 unit = " + fmt(options.metres_per_unit, 5) + " m, " +
        std::to_string(options.start_points.size()) + " start points, in " + fmt(sw.seconds(), 2) + " s");
  return 0;
}

struct PlayArgs {
  pipeline::PlaySpaceRunConfig config;
  std::string objects = "auto", report;
  std::vector<std::string> probes;
  FloorOptions floors;
};

int run_play(const PlayArgs& a, const Common& c) {
  check_files({a.config.scene.path, a.config.map}, {a.config.image, a.report});
  ThreadLimit threads(c.threads);
  pipeline::PlaySpaceRunConfig config = a.config;
  config.scene.grouping = parse_grouping(a.objects);
  config.scene.floors = a.floors.floors();
  for (const std::string& p : a.probes) {
    const std::vector<double> v = parse_numbers(p, "--at");
    if (v.size() != 3) throw Error("--at takes X,Y,Z in the scene's units (got '" + p + "')");
    config.probes.push_back({v[0], v[1], v[2]});
  }
  const pipeline::PlaySpaceRun run = pipeline::play_space(config, c.logger());
  if (!a.report.empty()) write_text_file(a.report, pipeline::report_json(run));
  else std::cout << pipeline::report_json(run);
  return 0;
}

struct InfoArgs {
  std::string scene;
  std::string objects = "auto";
  bool list = false;
  std::string json_path;
};

/// What a level file brings besides its triangles, as "label: text" lines.
void print_level(const LevelData& level) {
  for (const auto& [label, text] : level.info_lines()) {
    std::string head = label + ":";
    head.resize(std::max<size_t>(head.size() + 1, 20), ' ');
    std::cout << head << text << '\n';
  }
}

int run_info(const InfoArgs& a, const Common& c) {
  check_files({a.scene}, {a.json_path});
  const pipeline::SceneInfo info = pipeline::scene_info(a.scene, parse_grouping(a.objects));
  const Scene& scene = info.scene;
  std::cout << "scene:              " << a.scene << '\n'
            << "triangles:          " << scene.triangle_count() << " (" << scene.degenerate_dropped
            << " degenerate dropped)\n"
            << "objects:            " << scene.object_count() << " (grouping: " << to_string(scene.grouping) << ")\n"
            << "bounds:             " << describe_box(scene.bounds) << '\n'
            << "closed objects:     " << info.closed_objects << '\n'
            << "solid objects:      " << info.solid_objects << " (closed, consistently oriented, outward)\n"
            << "empty space detect: " << info.empty_space.reason << '\n'
            << "non-axis-aligned:   " << fmt(100.0 * scene.non_axis_aligned_share(), 2) << "% of "
            << fmt(scene.surface_area, 1) << " surface area\n";
  if (info.level) print_level(*info.level);
  if (a.list) {
    std::cout << "\n#id\ttriangles\tclosed\toriented\tsolid\trendered\toccluder\tname\n";
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const ObjectInfo& o = scene.objects[i];
      std::cout << i << '\t' << o.triangle_count << '\t' << o.closed << '\t' << o.oriented << '\t' << o.solid()
                << '\t' << o.rendered << '\t' << o.occluder << '\t' << o.name << '\n';
    }
  }
  if (!a.json_path.empty()) {
    pipeline::write_report(a.json_path, info);
    c.log("viewcells: wrote " + a.json_path);
  }
  return 0;
}

struct SampleArgs {
  SamplingOptions sampling;
  std::string output, report;
  bool measure_raw = false;
};

int run_sample(const SampleArgs& a, const Common& c) {
  check_files({a.sampling.scene}, {a.output, a.report});
  ThreadLimit threads(c.threads);
  pipeline::SampleConfig config;
  config.scene = a.sampling.source();
  config.sampling = a.sampling.sampler(c.quiet);
  config.segments_path = a.output;
  config.measure_raw = a.measure_raw;
  const pipeline::SampleResult result = pipeline::sample(config, c.logger());
  write_report_to(a.report, result, c);
  return 0;
}

}  // namespace

void add_scene_commands(CLI::App& app, const Common& common, Commands& commands) {
  auto gen = std::make_shared<GenerateArgs>();
  auto* g = app.add_subcommand("generate", "Write a generated test scene as OBJ (one group per object)");
  g->add_option("kind", gen->kind, "office | city | rotated-office | town (a city that is not a grid: districts with streets at their own angles, open squares, landmark towers) | glass-city (the city with glass curtain walls and pools of water: see-through surfaces, written with a .mtl beside the .obj)")->required();
  g->add_option("--seed", gen->seed, "Random seed (same seed, same scene)")
      ->capture_default_str()
      ->check(whole(0, UINT64_MAX));
  g->add_option("--size", gen->size,
                "Scale >= 1: office rooms and floors, city blocks per side (city 20 ~ 1M triangles)")
      ->capture_default_str();
  g->add_option("-o,--output", gen->output, "Output .obj file")->required();
  commands.push_back({g, [gen, &common] { return run_generate(*gen, common); }});

  auto cv = std::make_shared<ConvertArgs>();
  auto* co = app.add_subcommand(
      "convert", "Write a scene as a glTF level (.glb, y-up, metres): its rendered objects as meshes in object order "
                 "(a Quake 3 map's surfaces, its sky included), nothing else (a map's brushes, leaves and entities "
                 "are left behind)");
  co->add_option("scene", cv->scene, "Scene file (.obj, .ply, .off, .stl, .gltf, .glb, a Quake 3 .bsp, ...)")->required();
  co->add_option("-o,--output", cv->output, "The .glb file to write")->required();
  co->add_option("--objects", cv->objects, "Object grouping: auto | groups | components | triangles | nodes | meshes")
      ->capture_default_str();
  co->add_option("--metres-per-unit", cv->metres_per_unit,
                 "Metres in one unit of the scene (default: the file's own; 1/32 for a Quake 3 map, whose 56-unit "
                 "player is then 1.75 m tall; 1 when the file does not say)")
      ->check(CLI::PositiveNumber);
  co->add_flag("--start-points", cv->start_points,
               "Also write where players start, as empty nodes named 'spawn N' (a Quake 3 map's spawn entities)");
  commands.push_back({co, [cv, &common] { return run_convert(*cv, common); }});

  auto pl = std::make_shared<PlayArgs>();
  auto* ps = app.add_subcommand(
      "play-space",
      "Find where players stand on a scene from its geometry (walkable floors with room for a player, reachable "
      "by walking, stepping and dropping from start points; bake's default view space where it finds one) and "
      "report it; with --map, check it against the Quake 3 map the scene was converted from");
  ps->add_option("scene", pl->config.scene.path, "The scene (glTF, OBJ, ...)")->required();
  ps->add_option("--objects", pl->objects, "Object grouping: auto | groups | components | triangles | nodes | meshes")
      ->capture_default_str();
  ps->add_option("--map", pl->config.map,
                 "The Quake 3 map (.bsp) the scene was converted from (viewcells convert): report how much of the "
                 "map's play space (its eye band) the one found covers, and how much it adds outside");
  ps->add_option("--points", pl->config.points, "With --map: uniform points that measure the volumes")
      ->capture_default_str()
      ->check(whole(1, 1'000'000'000));
  ps->add_option("--seed", pl->config.seed, "With --map: seed of the points")
      ->capture_default_str()
      ->check(whole(0, UINT64_MAX));
  ps->add_option("--image", pl->config.image,
                 "With --map: a top-down PNG, green where both play spaces hold a floor's eye band, red where only "
                 "the map's does, blue where only the one found does");
  ps->add_option("--image-width", pl->config.image_width, "Width of the picture in pixels")
      ->capture_default_str()
      ->check(whole(16, 8192));
  ps->add_option("--at", pl->probes, "Say whether a player's eye can be at X,Y,Z (scene units; repeatable)");
  ps->add_option("--report", pl->report, "JSON report (default: printed)");
  add_floor_options(ps, pl->floors);
  commands.push_back({ps, [pl, &common] { return run_play(*pl, common); }});

  auto info = std::make_shared<InfoArgs>();
  auto* i = app.add_subcommand("info", "Describe a scene: objects, triangles, bounds, closedness, axis alignment");
  i->add_option("scene", info->scene, "Scene file (.obj, .ply, .off, .stl, or a Quake 3 .bsp)")->required();
  i->add_option("--objects", info->objects, "Object grouping: auto | groups | components | triangles | nodes | meshes (nodes and meshes: glTF, FBX and other formats read through Assimp; auto there means nodes)")
      ->capture_default_str();
  i->add_flag("--list", info->list, "List every object");
  i->add_option("--json", info->json_path, "Also write the description as JSON");
  commands.push_back({i, [info, &common] { return run_info(*info, common); }});

  auto smp = std::make_shared<SampleArgs>();
  auto* s = app.add_subcommand("sample", "Cast visibility segments through the view space (paper section 4.1)");
  add_sampling_options(s, smp->sampling);
  s->add_option("-o,--output", smp->output, "Segment file to write (.vseg)");
  s->add_option("--report", smp->report, "JSON report: settings, effects enabled and why, counts, timings");
  s->add_flag("--measure-raw", smp->measure_raw,
              "Also cast the same rays (re-casts included) through Embree alone; report raw_rays_per_second");
  commands.push_back({s, [smp, &common] { return run_sample(*smp, common); }});

  auto supported = std::make_shared<bool>(false);
  auto* is = app.add_subcommand("isa", "Print the Embree ISA that ray casting would use (see --embree-isa)");
  is->add_flag("--supported", *supported, "Print every ISA this CPU runs instead, one per line, best last");
  commands.push_back({is, [supported] {
                        if (*supported) {
                          for (const std::string& name : supported_embree_isas()) std::cout << name << '\n';
                        } else {
                          std::cout << embree_isa() << '\n';
                        }
                        return 0;
                      }});
}

}  // namespace viewcells::cli
