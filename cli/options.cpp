#include "options.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "viewcells/core/paths.h"
#include "viewcells/core/ranks.h"
#include "viewcells/core/error.h"
#include "viewcells/core/binary_file.h"

namespace viewcells::cli {

void Common::log(const std::string& s) const {
  if (!quiet && ranks::writer()) std::cerr << s << '\n';
}

pipeline::Log Common::logger() const {
  const bool q = quiet || !ranks::writer();  // on a cluster, rank 0 speaks for the run
  return [q](const std::string& s) {
    if (!q) std::cerr << s << '\n';
  };
}

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

namespace {

/// A validator of one finite number that `ok` accepts; `wanted` completes "give ...".
CLI::Validator number_check(std::function<bool(double)> ok, const std::string& wanted, const std::string& name) {
  return CLI::Validator(
      [ok, wanted](const std::string& text) -> std::string {
        try {
          size_t used = 0;
          const double v = std::stod(text, &used);
          if (used == text.size() && std::isfinite(v) && ok(v)) return "";
        } catch (const std::exception&) {
        }
        return "'" + text + "' is not allowed: give " + wanted;
      },
      name);
}

std::string short_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

}  // namespace

CLI::Validator non_negative() {
  return number_check([](double v) { return v >= 0; }, "a number of at least 0", "NUMBER >= 0");
}

CLI::Validator in_range(double lo, double hi) {
  const std::string range = short_number(lo) + " to " + short_number(hi);
  return number_check([lo, hi](double v) { return v >= lo && v <= hi; }, "a number from " + range,
                      "NUMBER in [" + short_number(lo) + ", " + short_number(hi) + "]");
}

std::pair<uint32_t, uint32_t> parse_size(const std::string& text, const std::string& option, uint32_t max) {
  long w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%ld%c%ld%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 ||
      h < 1 || w > max || h > max)
    throw Error(option + " needs WIDTHxHEIGHT, each from 1 to " + std::to_string(max) + ", e.g. 1024x768 (got '" +
                text + "')");
  return {static_cast<uint32_t>(w), static_cast<uint32_t>(h)};
}

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

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

void check_no_empty_values(const CLI::App& command) {
  for (const CLI::Option* o : command.get_options())
    for (const std::string& value : o->results())
      if (value.empty()) throw Error(o->get_name() + " was given an empty value: give a name or leave the option out");
}

void check_files(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                 const std::vector<std::string>& directories) {
  namespace fs = std::filesystem;
  auto key = [](const std::string& p) { return path_key(p).string(); };
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
  for (const std::string& dir : directories) {
    if (dir.empty()) continue;
    std::error_code ec;
    if (fs::exists(fs::symlink_status(dir, ec)) && !fs::is_directory(dir, ec))
      throw Error(dir, 0, "exists and is not a directory: it is asked for as a directory");
    const std::string k = key(dir);
    for (size_t i = 0; i < seen.size(); ++i)
      if (seen[i].first == k)
        throw Error(dir, 0, std::string("is a directory this command writes, and also given as ") +
                                (i < input_count ? "an input" : "an output file") + " (" + seen[i].second +
                                "); give another directory");
    seen.push_back({k, dir});
  }
}

pipeline::SceneSource SamplingOptions::source() const {
  pipeline::SceneSource s;
  s.path = scene;
  s.grouping = parse_grouping(objects);
  s.robust = !fast;
  s.floors = floors.floors();
  return s;
}

FloorSpaceConfig FloorOptions::floors() const {
  FloorSpaceConfig c = config;
  if (!eye_band.empty()) {
    const std::vector<double> v = parse_numbers(eye_band, "--eye-band");
    if (v.size() != 2 || !(v[0] >= 0 && v[1] > v[0]))
      throw Error("--eye-band takes LO,HI in metres above the floor, 0 <= LO < HI (got '" + eye_band + "')");
    c.eye_low = v[0];
    c.eye_high = v[1];
  }
  for (const std::string& s : starts) {
    const std::vector<double> v = parse_numbers(s, "--start");
    if (v.size() != 3) throw Error("--start takes X,Y,Z in the scene's units (got '" + s + "')");
    c.start_points.push_back({v[0], v[1], v[2]});
  }
  return c;
}

void add_floor_options(CLI::App* cmd, FloorOptions& a) {
  FloorSpaceConfig& c = a.config;
  const std::string g = "Play space from floors (scenes other than Quake 3 maps)";
  cmd->add_option("--metres-per-unit", c.metres_per_unit,
                  "Metres in one unit of the scene (default: the file's own: 1 for glTF, 1/32 for a Quake 3 map; "
                  "1 when the file does not say, e.g. OBJ)")
      ->check(CLI::PositiveNumber)
      ->group(g);
  cmd->add_option("--start", a.starts,
                  "Where players start, X,Y,Z in scene units (repeatable; default: the file's spawn nodes, else every "
                  "floor region of at least --min-region)")
      ->group(g);
  cmd->add_flag("--only-from-starts", c.only_from_starts,
               "With start points: only what they reach (default: also every floor region of at least --min-region "
               "within --region-margin of it, since walking misses jump pads and teleporters)")
      ->group(g);
  cmd->add_option("--region-margin", c.region_margin,
                  "With start points: floor regions join within this many metres (horizontally) of what they reach")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(g);
  cmd->add_option("--player-height", c.player_height, "Free space a standing player needs above a floor, metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->group(g);
  cmd->add_option("--step", c.step, "Highest step a player walks up, metres")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(g);
  cmd->add_option("--eye-band", a.eye_band, "Eye heights above a floor, LO,HI metres (crouch to jump; default 1,3)")
      ->group(g);
  cmd->add_option("--walk-normal", c.walk_normal, "Least z of a walkable floor's unit normal (0.7: 45.6 degrees)")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str()
      ->group(g);
  cmd->add_option("--floor-cell", c.cell, "Spacing of the columns of rays that find the floors, metres")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str()
      ->group(g);
  cmd->add_option("--min-region", c.min_region,
                  "Floor regions at least this large are starts (with start points too, unless --only-from-starts), "
                  "square metres")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(g);
}

SamplerConfig SamplingOptions::sampler(const Common& c) const {
  SamplerConfig config;
  config.samples = samples;
  config.target_segments = segments;
  config.seed = seed;
  config.empty_space = parse_empty_space_mode(empty_space);
  config.max_recasts = max_recasts;
  config.show_progress = !c.quiet;
  if (!view_box.empty()) config.view_box = parse_box(view_box);
  return config;
}

void add_sampling_options(CLI::App* cmd, SamplingOptions& a) {
  cmd->add_option("scene", a.scene, "Scene file (.obj, .ply, .off, .stl, or a Quake 3 .bsp)")->required();
  auto* samples_opt = cmd->add_option("--samples", a.samples, "Number of samples (two rays each)")
                          ->capture_default_str()
                          ->check(whole(1, kMaxSamples));
  cmd->add_option("--segments", a.segments, "Sample until this many valid segments exist (instead of --samples)")
      ->check(whole(1, kMaxSamples))
      ->excludes(samples_opt);
  cmd->add_option("--seed", a.seed, "Random seed (same seed, same result for any --threads)")
      ->capture_default_str()
      ->check(whole(0, UINT64_MAX));
  cmd->add_option("--objects", a.objects, "Object grouping: auto | groups | components | triangles | nodes | meshes (nodes and meshes: glTF, FBX and other formats read through Assimp; auto there means nodes)")
      ->capture_default_str();
  cmd->add_option("--view-box", a.view_box, "View space box xmin,ymin,zmin,xmax,ymax,zmax (default: scene bounds)");
  cmd->add_option("--empty-space", a.empty_space,
                  "Empty view space detection: auto (only for closed, outward-oriented scenes) | on | off")
      ->capture_default_str();
  cmd->add_option("--max-recasts", a.max_recasts, "Re-casts per sample when empty space detection is on")
      ->capture_default_str();
  cmd->add_flag("--fast", a.fast, "Embree without robust mode (faster, may leak through edges)");
}

namespace {

void parse_screen(const std::string& text, CostModel& model) {
  const auto [w, h] = parse_size(text, "--screen", 65536);
  model.screen_width = static_cast<int>(w);
  model.screen_height = static_cast<int>(h);
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

}  // namespace

CostModel CellOptions::model() const {
  CostModel m;
  m.a = cost_a;
  m.b = cost_b;
  m.c = cost_c;
  parse_screen(screen, m);
  m.fov_degrees = fov;
  m.validate();
  return m;
}

SubdivisionConfig CellOptions::subdivision(const Common& c, const SamplingOptions& s) const {
  SubdivisionConfig config;
  config.max_cells = max_cells;
  config.geometry_aligned = no_ga ? GeometryAlignedMode::kOff : (ga ? GeometryAlignedMode::kOn : GeometryAlignedMode::kAuto);
  config.ga_candidates = ga_candidates;
  config.max_axis_candidates = axis_candidates;
  config.exact_candidates = exact_candidates;
  config.min_reduction = min_reduction;
  config.density = parse_density_band(density_band);
  config.play_space = play_space;
  config.seed = s.seed;
  config.show_progress = !c.quiet;
  return config;
}

std::optional<AgvsConfig> MergeOptions::agvs(const Common& c, uint64_t seed, uint64_t construction_samples) const {
  if (pvs == "samples") {
    if (samples || pixel_error > 0) throw Error("--merge-samples and --merge-pixel-error need --merge-pvs agvs");
    return std::nullopt;
  }
  AgvsConfig a;
  a.seed = seed + 7'000'001;  // not the construction samples' stream
  a.max_samples = samples;
  a.pixel_error = pixel_error;
  a.mutation_lanes = lanes;
  if (!samples && !(pixel_error > 0)) a.max_samples = std::max<uint64_t>(construction_samples, 1);
  a.show_progress = !c.quiet;
  return a;
}

void add_merge_options(CLI::App* cmd, MergeOptions& a) {
  cmd->add_option("--merge-pvs", a.pvs,
                  "What merging decides on: agvs (the elementary cells' PVSs from the construction samples united with "
                  "an AGVS run over the cells, and greedy merging started from the subdivision's own cut that "
                  "held-out samples score best: a second AGVS run and four times as many random samples as the "
                  "construction drew, no count rated worse than the subdivision's own cut by either (0.2% from 16 cells up and "
                  "2% below for histories within refined blocks at low counts); the choice is made again "
                  "below each barrier where the cut is the subdivision's) or samples (greedy merging on the "
                  "construction samples' PVSs alone: a few hundred per cell, whose gaps it fits)")
      ->capture_default_str()
      ->check(CLI::IsMember({"agvs", "samples"}));
  cmd->add_option("--merge-samples", a.samples,
                  "AGVS samples of each of the two runs over the elementary cells (one to merge on, one held out to "
                  "choose where greedy merging starts; default, without --merge-pixel-error: --samples)")
      ->check(whole(1, kMaxSamples));
  cmd->add_option("--merge-pixel-error", a.pixel_error,
                  "Run each AGVS run over the elementary cells until its estimated pixel error (of 1024x1024) is at "
                  "most this")
      ->check(positive());
  cmd->add_option("--merge-mutation-lanes", a.lanes,
                  "Mutation lanes of those AGVS runs (as pvs --mutation-lanes: more lanes spread the mutations over "
                  "threads and cluster ranks; the result depends on it, not on the threads or ranks)")
      ->capture_default_str()
      ->check(whole(1, 65536));
}

void add_cell_options(CLI::App* cmd, CellOptions& a, const std::string& max_cells_help) {
  if (!max_cells_help.empty())
    cmd->add_option("--max-cells", a.max_cells, max_cells_help)->capture_default_str()->check(whole(1, kMaxCells));
  auto* no_ga = cmd->add_flag("--no-ga", a.no_ga, "No geometry-aligned split candidates");
  cmd->add_flag("--ga", a.ga, "Geometry-aligned candidates even for mostly axis-aligned scenes")->excludes(no_ga);
  cmd->add_option("--ga-candidates", a.ga_candidates, "Geometry-aligned planes tried per cell at most")
      ->capture_default_str();
  cmd->add_option("--axis-candidates", a.axis_candidates, "Axis-aligned positions tried per axis and cell at most")
      ->capture_default_str()
      ->check(positive());
  cmd->add_flag("--exact-candidates", a.exact_candidates, kExactCandidatesHelp);
  cmd->add_option("--min-reduction", a.min_reduction,
                  "Stop when splits reduce the cost by less than this share of the initial cost for 50 splits running")
      ->capture_default_str();
  cmd->add_option("--cost-a", a.cost_a, "Render cost model: minimum cost of an object (r = max(a, b * triangles))")
      ->capture_default_str();
  cmd->add_option("--cost-b", a.cost_b, "Render cost model: cost per triangle")->capture_default_str();
  cmd->add_option("--cost-c", a.cost_c,
                  "Render cost model: cost per projected pixel, estimated per cell from its corners and centre "
                  "(0: no pixel term, nothing estimated)")
      ->capture_default_str();
  cmd->add_option("--screen", a.screen, "Screen WIDTHxHEIGHT the pixel term assumes (with --cost-c)")
      ->capture_default_str();
  cmd->add_option("--fov", a.fov, "Horizontal field of view in degrees the pixel term assumes (with --cost-c)")
      ->capture_default_str();
  cmd->add_option("--density-band", a.density_band,
                  "Viewpoint density zlo,zhi[,outside]: weight 1 between the heights, outside (default 0.1) elsewhere");
  auto* play = cmd->add_flag(
      "--play-space", a.play_space,
      std::string("Quake 3 maps: weigh cells by their volume where a player's eye can be (non-solid leaves reachable "
                  "from the spawn points, at most 112 units above a walkable floor) instead of all non-solid space, so "
                  "merging spends the cells where players are") +
          (a.play_space_by_default ? " (the default on a Quake 3 map unless --density-band or --view-box is given)"
                                   : ""));
  if (a.play_space_by_default)
    cmd->add_flag("--no-play-space", a.no_play_space,
                  "Quake 3 maps: weigh cells by their volume in all of the map's non-solid space, not the play space")
        ->excludes(play);
}

pipeline::CutRule CutOptions::rule() const {
  pipeline::CutRule r;
  r.count = count;
  r.memory_given = !memory.empty();
  if (r.memory_given) r.memory = parse_bytes(memory);
  r.cost_ratio = cost_ratio;
  return r;
}

void add_cut_options(CLI::App* app, CutOptions& a) {
  app->add_option("--count", a.count, "Exactly this many view cells")->check(whole(1, kMaxCells));
  app->add_option("--memory", a.memory,
                  "The most view cells whose .pvs file, as compress writes it (point location, hierarchy and "
                  "compressed PVSs), fits this budget, measured (bytes; K, M, G allowed)");
  app->add_option("--cost-ratio", a.cost_ratio,
                  "The fewest view cells whose render cost is within this ratio (>= 1) of the elementary cells'");
}

void add_view_options(CLI::App* app, pipeline::ViewsConfig& v, const std::string& mesh_help,
                      const std::string& png_help) {
  app->add_option("--mesh", v.mesh, mesh_help);
  app->add_option("--slice-png", v.slice_png, png_help);
  app->add_option("--slice-z", v.slice_z, "Height of the slice (default: middle of the view space)");
  app->add_option("--slice-width", v.slice_width, "Slice image width in pixels")
      ->capture_default_str()
      ->check(whole(16, 16384));
}

}  // namespace viewcells::cli
