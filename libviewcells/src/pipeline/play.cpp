/// `viewcells play-space` (pipeline/play.h).
#include "viewcells/pipeline/play.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/progress.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/vis/cell_views.h"
#include "viewcells/vis/level_view.h"

namespace viewcells::pipeline {

PlaySpaceRun play_space(const PlaySpaceRunConfig& config, const Log& log) {
  if (!config.image.empty() && config.map.empty())
    throw Error("--image draws the found play space against a map's: give --map");
  if (config.points == 0) throw Error("--points must be positive");
  Stopwatch sw;
  PlaySpaceRun out;
  out.config = config;
  const LoadedScene loaded = load_scene_for_rays(config.scene, log);
  const FloorSpace found = find_floor_space(*loaded.scene, *loaded.caster, config.scene.floors);
  out.seconds = sw.seconds();
  out.rule = found.rule();
  out.found = !found.empty();
  out.metres_per_unit = found.metres_per_unit();
  const double k = out.metres_per_unit;
  out.volume_m3 = found.volume() * k * k * k;
  out.floor_area_m2 = found.floor_area() * k * k;
  out.spans = found.spans();
  out.reached_spans = found.reached_spans();
  out.box = found.box();
  for (const Vec3& p : config.probes) {
    out.probes_in.push_back(found.contains(p));
    log("viewcells: (" + fmt(p.x) + ", " + fmt(p.y) + ", " + fmt(p.z) + ") is " +
        (out.probes_in.back() ? "in" : "not in") + " the play space");
  }
  log(std::string("viewcells: play space ") + (out.found ? "found" : "not found") + " in " + fmt(out.seconds, 2) + " s: " + out.rule +
      (out.found ? "; eye band " + fmt(out.volume_m3, 1) + " m^3" : std::string()));
  if (config.map.empty()) return out;
  sw.restart();
  SceneSource map_source;
  map_source.path = config.map;
  const LoadedScene map_scene = load_scene_for_rays(map_source, log);
  if (!map_scene.level || !map_scene.level->view_space())
    throw Error(config.map, 0, "--map takes a level that knows its own play space (a Quake 3 map, .bsp)");
  // The found space's units per map unit: the converted level's vertices are the map's times this.
  const double map_mpu = map_scene.scene->metres_per_unit;
  const double scale = map_mpu / k;
  const PlaySpaceComparison o =
      map_scene.level->compare_play_space(*map_scene.scene, *map_scene.caster, found, scale, config.points, config.seed,
                                          config.image.empty() ? 0 : config.image_width);
  PlaySpaceRun::Overlap r;
  const double m3 = map_mpu * map_mpu * map_mpu;
  r.map_m3 = o.reference_volume * m3;
  r.found_m3 = o.found_volume * m3;
  r.both_m3 = o.both_volume * m3;
  r.coverage = o.coverage();
  r.excess = o.excess();
  r.points = o.points;
  r.map_rule = o.reference_rule;
  r.seconds = sw.seconds();
  out.overlap = r;
  log("viewcells: against " + config.map + "'s play space (" + fmt(r.map_m3, 1) + " m^3 of eye band): covers " +
      fmt(100 * r.coverage, 1) + "%, adds " + fmt(100 * r.excess, 1) + "% outside it (" + std::to_string(r.points) +
      " points, " + fmt(r.seconds, 1) + " s)");
  if (!config.image.empty()) {
    write_rgb_png(config.image, o.width, o.height, o.rgb);
    log("viewcells: picture -> " + config.image +
        " (top down: green both, red only the map's play space, blue only the one found)");
  }
  return out;
}

namespace {
/// Why a level that knows its own view space gets no play space from floors.
std::string level_play_space(const std::string& kind) {
  return "not drawn: a " + kind + "'s play space is its own view space, not found from floors";
}
}  // namespace

FoundPlaySpace find_play_space(const SceneSource& source, const Log& log) {
  FoundPlaySpace out;
  out.loaded = load_scene_for_rays(source, log);
  if (out.loaded.level && out.loaded.level->view_space()) {
    out.why = level_play_space(out.loaded.level->kind());
    return out;
  }
  auto space = std::make_shared<FloorSpace>(find_floor_space(*out.loaded.scene, *out.loaded.caster, source.floors));
  out.why = space->rule();
  if (!space->empty()) out.space = std::move(space);
  return out;
}

GroupedMesh floor_mesh(const FloorSpace& space, double lift_m) {
  GroupedMesh m;
  const double lift = lift_m / space.metres_per_unit();
  for (const FloorSpace::FloorRect& r : space.floor_rects()) {
    const auto base = static_cast<uint32_t>(m.positions.size() / 3);
    const float z = static_cast<float>(r.z + lift);
    for (const auto& [x, y] : {std::pair{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}})
      m.positions.insert(m.positions.end(), {static_cast<float>(x), static_cast<float>(y), z});
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  m.first_vertex = {0, static_cast<uint32_t>(m.positions.size() / 3)};
  m.first_index = {0, static_cast<uint32_t>(m.indices.size())};
  return m;
}

void add_play_space(LevelView& view, const SceneSource& source, const Log& log) {
  // A level file (a Quake 3 map) brings its own view space: said without reading it again (the
  // scene in memory, as `view` hands it, is that file's triangles).
  if (const std::string kind = level_format_name(source.path); !kind.empty()) {
    view.play_space_rule = level_play_space(kind);
    return;
  }
  const FoundPlaySpace found = find_play_space(source, log);
  view.play_space_rule = found.why;
  if (found.space) view.play_space = floor_mesh(*found.space);
}

std::string report_json(const PlaySpaceRun& run) {
  using nlohmann::json;
  const FloorSpaceConfig& f = run.config.scene.floors;
  json j = {{"command", "play-space"},
            {"scene", run.config.scene.path},
            {"embree_isa", embree_isa()},
            {"settings",
             {{"metres_per_unit", run.metres_per_unit},
              {"cell_m", f.cell},
              {"walk_normal", f.walk_normal},
              {"player_height_m", f.player_height},
              {"step_m", f.step},
              {"eye_band_m", {f.eye_low, f.eye_high}},
              {"min_region_m2", f.min_region},
              {"region_margin_m", f.region_margin},
              {"only_from_starts", f.only_from_starts},
              {"start_points_given", f.start_points.size()}}},
            {"found", run.found},
            {"rule", run.rule},
            {"eye_band_m3", run.volume_m3},
            {"floor_area_m2", run.floor_area_m2},
            {"spans", run.spans},
            {"reached_spans", run.reached_spans},
            {"seconds", run.seconds}};
  json probes = json::array();
  for (size_t i = 0; i < run.probes_in.size(); ++i) {
    const Vec3& p = run.config.probes[i];
    probes.push_back({{"at", {p.x, p.y, p.z}}, {"in", static_cast<bool>(run.probes_in[i])}});
  }
  j["probes"] = probes;
  if (run.overlap) {
    const PlaySpaceRun::Overlap& o = *run.overlap;
    j["against_map"] = {{"map", run.config.map},
                        {"map_play_space", o.map_rule},
                        {"map_eye_band_m3", o.map_m3},
                        {"found_eye_band_m3", o.found_m3},
                        {"both_m3", o.both_m3},
                        {"coverage", o.coverage},
                        {"excess", o.excess},
                        {"points", o.points},
                        {"seed", run.config.seed},
                        {"seconds", o.seconds}};
  }
  return j.dump(2) + "\n";
}

}  // namespace viewcells::pipeline
