#include "viewcells/pipeline/options.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <type_traits>

#include "viewcells/core/error.h"
#include "viewcells/scene/scene.h"

namespace viewcells::pipeline {

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
  const std::string unit = text.substr(used);
  double scale = 1;
  if (unit == "K" || unit == "k" || unit == "KB") scale = 1024.0;
  else if (unit == "M" || unit == "MB") scale = 1024.0 * 1024;
  else if (unit == "G" || unit == "GB") scale = 1024.0 * 1024 * 1024;
  else if (!unit.empty() && unit != "B") used = 0;
  if (used == 0 || !(v >= 0) || !std::isfinite(v * scale) || v * scale > 1e18)
    throw Error("--memory needs a size in bytes, e.g. 65536, 64K, 2M or 1G (got '" + text + "')");
  return static_cast<uint64_t>(v * scale);
}

double parse_percent(const std::string& text, const std::string& option) {
  std::string number = text;
  if (!number.empty() && number.back() == '%') number.pop_back();
  const std::vector<double> v = parse_numbers(number, option);
  if (v.size() != 1 || !(v[0] > 0 && v[0] <= 100))
    throw Error(option + " needs a percentage above 0 and at most 100, e.g. 1% (got '" + text + "')");
  return v[0] / 100;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
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

SceneSource SamplingOptions::source() const {
  SceneSource s;
  s.path = scene;
  s.grouping = parse_grouping(objects);
  s.robust = !fast;
  s.floors = floors.floors();
  return s;
}

SamplerConfig SamplingOptions::sampler(bool quiet) const {
  SamplerConfig config;
  config.samples = samples;
  config.target_segments = segments;
  config.seed = seed;
  config.empty_space = parse_empty_space_mode(empty_space);
  config.max_recasts = max_recasts;
  config.show_progress = !quiet;
  if (!view_box.empty()) config.view_box = parse_box(view_box);
  return config;
}

namespace {

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
  const auto [w, h] = parse_size(screen, "--screen", 65536);
  m.screen_width = static_cast<int>(w);
  m.screen_height = static_cast<int>(h);
  m.fov_degrees = fov;
  m.validate();
  return m;
}

SubdivisionConfig CellOptions::subdivision(bool quiet, const SamplingOptions& s) const {
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
  config.show_progress = !quiet;
  return config;
}

std::optional<AgvsConfig> MergeOptions::agvs(bool quiet, uint64_t seed, uint64_t construction_samples) const {
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
  a.show_progress = !quiet;
  return a;
}

BakeOptions::BakeOptions() {
  cells.max_cells = 0;  // 4 x cells, or 4096 with a memory budget (resolve)
}

BakeConfig BakeOptions::config(bool quiet) const {
  if (bound.cells == 0 && memory.empty()) throw Error("bake needs a budget: --cells N or --memory BYTES");
  for (const std::string& flag : given)
    if (const BakeOption* o = find_bake_option(flag))
      for (const std::string& other : o->excludes)
        if (given.count(other)) throw Error(flag + " excludes " + other);
  BakeConfig config = bound;
  config.model = cells.model();
  config.subdivision = cells.subdivision(quiet, sampling);
  config.play_space_where_known = !cells.no_play_space;
  config.scene = sampling.source();
  config.sampling = sampling.sampler(quiet);
  config.merge_on_agvs = merge.pvs == "agvs";
  config.merge_agvs = merge.agvs(quiet, sampling.seed, config.sampling.samples);
  config.memory = memory.empty() ? 0 : parse_bytes(memory);
  if (!memory.empty() && config.memory == 0) throw Error("--memory must be above 0 bytes (got '" + memory + "')");
  if (memory_of != "file" && memory_of != "lists") throw Error("--memory-of is file or lists, not '" + memory_of + "'");
  config.memory_of_lists = memory_of == "lists";
  config.holes = holes.empty() ? 0.0 : parse_percent(holes, "--holes");
  // The stop rule, the measuring cameras and their frames when not given: resolve() decides.
  if (!measure_size.empty())
    std::tie(config.frame.width, config.frame.height) = parse_size(measure_size, "--measure-size", 2048);
  std::tie(config.sample_frame.width, config.sample_frame.height) = parse_size(frame_size, "--frame-size", 2048);
  config.agvs = agvs;
  config.agvs.show_progress = !quiet;
  config.agvs.seed = sampling.seed;
  return config;
}

namespace {

std::string refused(const std::string& text, const std::string& wanted) {
  return "'" + text + "' is not allowed: give " + wanted;
}

}  // namespace

OptionCheck whole_check(uint64_t lo, uint64_t hi) {
  return [lo, hi](const std::string& text) -> std::string {
    uint64_t v = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < lo || v > hi)
      return refused(text, "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
    return "";
  };
}

OptionCheck number_check(std::function<bool(double)> ok, const std::string& wanted) {
  return [ok, wanted](const std::string& text) -> std::string {
    try {
      size_t used = 0;
      const double v = std::stod(text, &used);
      if (used == text.size() && std::isfinite(v) && ok(v)) return "";
    } catch (const std::exception&) {
    }
    return refused(text, wanted);
  };
}

// ---- the table ----

namespace {

using Kind = BakeOption::Kind;
using Check = OptionCheck;

std::string short_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// The numbers' checks and how help names them.
struct NumberRule {
  Check check;
  std::string type;
};
/// Any finite number (the cost model checks its own ranges, naming the field).
NumberRule any_number() { return {number_check([](double) { return true; }, "a finite number"), ""}; }
NumberRule positive() { return {number_check([](double v) { return v > 0; }, "a number above 0"), "NUMBER > 0"}; }
NumberRule non_negative() {
  return {number_check([](double v) { return v >= 0; }, "a number of at least 0"), "NUMBER >= 0"};
}
NumberRule in_range(double lo, double hi) {
  return {number_check([lo, hi](double v) { return v >= lo && v <= hi; },
                       "a number from " + short_number(lo) + " to " + short_number(hi)),
          "NUMBER in [" + short_number(lo) + ", " + short_number(hi) + "]"};
}

std::optional<bool> truth(const std::string& text) {
  if (text == "true" || text == "1" || text == "on" || text == "yes") return true;
  if (text == "false" || text == "0" || text == "off" || text == "no") return false;
  return std::nullopt;
}

/// A field of BakeOptions, for the table's setters: FIELD(cells.max_cells).
#define FIELD(member) [](BakeOptions& o) -> auto& { return o.member; }

template <class Get>
BakeOption whole(const std::string& flag, Get get, uint64_t lo, uint64_t hi, std::string help, bool show = false) {
  BakeOption o;
  o.flag = flag;
  o.kind = Kind::kWhole;
  o.type = "INT in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  o.help = std::move(help);
  o.show_default = show;
  o.check = whole_check(lo, hi);
  o.set = [get](BakeOptions& b, const std::string& text) {
    using T = std::remove_reference_t<decltype(get(b))>;
    get(b) = static_cast<T>(std::stoull(text));
  };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return std::to_string(get(copy));
  };
  return o;
}

template <class Get>
BakeOption number(const std::string& flag, Get get, const NumberRule& rule, std::string help, bool show = false) {
  BakeOption o;
  o.flag = flag;
  o.kind = Kind::kNumber;
  o.type = rule.type;
  o.help = std::move(help);
  o.show_default = show;
  o.check = rule.check;
  o.set = [get](BakeOptions& b, const std::string& text) { get(b) = std::stod(text); };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return short_number(get(copy));
  };
  return o;
}

/// Text parsed when the bake's config is made (sizes, boxes, bytes), or one of `members`.
template <class Get>
BakeOption text(const std::string& flag, Get get, std::string help, bool show = false,
                std::vector<std::string> members = {}) {
  BakeOption o;
  o.flag = flag;
  o.kind = Kind::kText;
  o.help = std::move(help);
  o.show_default = show;
  if (!members.empty()) {
    std::string list, said;
    for (size_t i = 0; i < members.size(); ++i) {
      list += (i ? "," : "") + members[i];
      said += (i == 0 ? "" : i + 1 == members.size() ? " or " : ", ") + members[i];
    }
    o.type = "{" + list + "}";
    o.check = [members, said](const std::string& t) {
      return std::find(members.begin(), members.end(), t) != members.end() ? "" : refused(t, said);
    };
  } else {
    o.check = [](const std::string&) { return std::string(); };
  }
  o.set = [get](BakeOptions& b, const std::string& t) { get(b) = t; };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return std::string(get(copy));
  };
  return o;
}

/// On when given (or given "true"); `negation` turns it off.
template <class Get>
BakeOption flag(const std::string& name, Get get, std::string help, const std::string& negation = "") {
  BakeOption o;
  o.flag = name;
  o.negation = negation;
  o.kind = Kind::kFlag;
  o.help = std::move(help);
  o.check = [](const std::string& t) { return truth(t) ? "" : refused(t, "true or false"); };
  o.set = [get](BakeOptions& b, const std::string& t) { get(b) = *truth(t); };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return std::string(get(copy) ? "true" : "false");
  };
  return o;
}

BakeOption excluding(BakeOption o, std::vector<std::string> flags) {
  o.excludes = std::move(flags);
  return o;
}

BakeOption in_group(BakeOption o, const std::string& group) {
  o.group = group;
  return o;
}

std::vector<BakeOption> make_table() {
  std::vector<BakeOption> t;
  // The scene and its sampling (also sample, build and compare's).
  t.push_back(excluding(whole("--samples", FIELD(sampling.samples), 1, kMaxSamples, "Number of samples (two rays each)", true),
                        {"--segments"}));
  t.push_back(excluding(whole("--segments", FIELD(sampling.segments), 1, kMaxSamples,
                              "Sample until this many valid segments exist (instead of --samples)"),
                        {"--samples"}));
  t.push_back(whole("--seed", FIELD(sampling.seed), 0, UINT64_MAX, "Random seed (same seed, same result for any --threads)",
                    true));
  t.push_back(text("--objects", FIELD(sampling.objects),
                   "Object grouping: auto | groups | components | triangles | nodes | meshes (nodes and meshes: glTF, "
                   "FBX and other formats read through Assimp; auto there means nodes)",
                   true));
  t.push_back(text("--view-box", FIELD(sampling.view_box),
                   "View space box xmin,ymin,zmin,xmax,ymax,zmax (default: scene bounds)"));
  t.push_back(text("--empty-space", FIELD(sampling.empty_space),
                   "Empty view space detection: auto (only for closed, outward-oriented scenes) | on | off", true));
  t.push_back(whole("--max-recasts", FIELD(sampling.max_recasts), 0, 1000, "Re-casts per sample when empty space detection is on",
                    true));
  t.push_back(flag("--fast", FIELD(sampling.fast), "Embree without robust mode (faster, may leak through edges)"));
  // The budget.
  t.push_back(excluding(whole("--cells", FIELD(bound.cells), 1, kMaxCells, "Budget: this many view cells"), {"--memory"}));
  t.push_back(excluding(text("--memory", FIELD(memory),
                             "Budget: a .pvs file of at most this many bytes (K, M, G allowed); the file written is "
                             "measured, and the cells are merged further until it fits"),
                        {"--cells"}));
  t.push_back(text("--memory-of", FIELD(memory_of),
                   "What --memory counts: file (the whole .pvs) or lists (the visible sets alone as an engine's compact "
                   "handle holds them: the coded lists and 8 bytes a hierarchy node, without point location and object "
                   "names; what stands against a map compiler's vis rows)",
                   true, {"file", "lists"}));
  t.push_back(whole("--max-cells", FIELD(cells.max_cells), 1, kMaxCells,
                    "Elementary cells to build before merging (default: 4 x --cells, or 4096 with --memory)"));
  // The subdivision and its cost model (also build's).
  t.push_back(excluding(flag("--no-ga", FIELD(cells.no_ga), "No geometry-aligned split candidates"), {"--ga"}));
  t.push_back(excluding(flag("--ga", FIELD(cells.ga), "Geometry-aligned candidates even for mostly axis-aligned scenes"),
                        {"--no-ga"}));
  t.push_back(whole("--ga-candidates", FIELD(cells.ga_candidates), 0, UINT32_MAX,
                    "Geometry-aligned planes tried per cell at most", true));
  t.push_back(whole("--axis-candidates", FIELD(cells.axis_candidates), 1, UINT32_MAX,
                    "Axis-aligned positions tried per axis and cell at most", true));
  t.push_back(flag("--exact-candidates", FIELD(cells.exact_candidates),
                   "Axis-aligned positions as the paper draws them: a uniform random subset of the distinct "
                   "segment-end coordinates of each cell, which needs them all sorted (about 3x slower subdivision on "
                   "large scenes). Default: random segment ends until --axis-candidates distinct ones, so that "
                   "coordinates where many segments end (walls) are likelier; both evaluate their positions exactly"));
  t.push_back(number("--min-reduction", FIELD(cells.min_reduction), non_negative(),
                     "Stop when splits reduce the cost by less than this share of the initial cost for 50 splits running",
                     true));
  t.push_back(number("--cost-a", FIELD(cells.cost_a), any_number(),
                     "Render cost model: minimum cost of an object (r = max(a, b * triangles))", true));
  t.push_back(number("--cost-b", FIELD(cells.cost_b), any_number(), "Render cost model: cost per triangle", true));
  t.push_back(number("--cost-c", FIELD(cells.cost_c), any_number(),
                     "Render cost model: cost per projected pixel, estimated per cell from its corners and centre "
                     "(0: no pixel term, nothing estimated)",
                     true));
  t.push_back(text("--screen", FIELD(cells.screen), "Screen WIDTHxHEIGHT the pixel term assumes (with --cost-c)", true));
  t.push_back(number("--fov", FIELD(cells.fov), any_number(),
                     "Horizontal field of view in degrees the pixel term assumes (with --cost-c)", true));
  t.push_back(text("--density-band", FIELD(cells.density_band),
                   "Viewpoint density zlo,zhi[,outside]: weight 1 between the heights, outside (default 0.1) elsewhere"));
  t.push_back(excluding(flag("--play-space", FIELD(cells.play_space),
                             "Quake 3 maps: weigh cells by their volume where a player's eye can be (non-solid leaves "
                             "reachable from the spawn points, at most 112 units above a walkable floor) instead of all "
                             "non-solid space, so merging spends the cells where players are (bake: the default on a Quake 3 "
                             "map unless --density-band or --view-box is given)"),
                        {"--no-play-space"}));
  t.push_back(excluding(flag("--no-play-space", FIELD(cells.no_play_space),
                             "Quake 3 maps: weigh cells by their volume in all of the map's non-solid space, not the "
                             "play space"),
                        {"--play-space"}));
  // Merging (also build's).
  t.push_back(text("--merge-pvs", FIELD(merge.pvs),
                   "What merging decides on: agvs (the elementary cells' PVSs from the construction samples united with "
                   "an AGVS run over the cells, and greedy merging started from the subdivision's own cut that "
                   "held-out samples score best: a second AGVS run and four times as many random samples as the "
                   "construction drew, no count rated worse than the subdivision's own cut by either (0.2% from 16 "
                   "cells up and 2% below for histories within refined blocks at low counts); the choice is made again "
                   "below each barrier where the cut is the subdivision's) or samples (greedy merging on the "
                   "construction samples' PVSs alone: a few hundred per cell, whose gaps it fits)",
                   true, {"agvs", "samples"}));
  t.push_back(whole("--merge-samples", FIELD(merge.samples), 1, kMaxSamples,
                    "AGVS samples of each of the two runs over the elementary cells (one to merge on, one held out to "
                    "choose where greedy merging starts; default, without --merge-pixel-error: --samples)"));
  t.push_back(number("--merge-pixel-error", FIELD(merge.pixel_error), positive(),
                     "Run each AGVS run over the elementary cells until its estimated pixel error (of 1024x1024) is at "
                     "most this"));
  t.push_back(whole("--merge-mutation-lanes", FIELD(merge.lanes), 1, 65536,
                    "Mutation lanes of those AGVS runs (as pvs --mutation-lanes: more lanes spread the mutations over "
                    "threads and cluster ranks; the result depends on it, not on the threads or ranks)",
                    true));
  // The PVSs' AGVS (also pvs's, where --agvs-time and --agvs-samples are --time and --samples).
  t.push_back(number("--pixel-error", FIELD(agvs.pixel_error), positive(),
                     "Stop when the estimated pixel error (pixels of a 1024x1024 image that differ) is at most this"));
  t.push_back(number("--agvs-time", FIELD(agvs.max_seconds), positive(), "Stop AGVS after this many seconds of sampling"));
  t.push_back(whole("--agvs-samples", FIELD(agvs.max_samples), 1, kMaxSamples,
                    "Stop after this many AGVS samples (checked between batches: a run may pass it by less than a "
                    "batch)"));
  t.push_back(whole("--batch", FIELD(agvs.batch_size), 1, 100'000'000, "Samples per batch", true));
  t.push_back(whole("--mutation-lanes", FIELD(agvs.mutation_lanes), 1, 65536,
                    "AGVS: independent lanes of mutation candidates, each with its own random stream and its share of "
                    "the buffer. Lanes are drawn and fed in parallel, on a cluster each by its own rank: give at least "
                    "as many as the cores of all nodes for a bake that scales. The result depends on it, not on the "
                    "threads or ranks",
                    true));
  t.push_back(number("--min-share", FIELD(agvs.min_share), in_range(0, 1),
                     "AGVS: share of every batch kept for view space-direction samples whatever their weight; they are "
                     "the pixel error estimator's camera rays (more: a finer estimate, fewer samples for the "
                     "mutations)",
                     true));
  // The bake's own.
  t.push_back(number("--time", FIELD(bound.max_seconds), positive(),
                     "Bound the whole bake to this many seconds: each of the merge's two AGVS runs stops at a quarter "
                     "of it, the PVSs' AGVS at three quarters of what is left, the near-object samples when it runs "
                     "out (a hierarchy that uses it all up is an error, and with --work is kept for a rerun). "
                     "--agvs-time bounds the PVSs' AGVS alone"));
  t.push_back(text("--work", FIELD(bound.work_dir),
                   "Work directory: keeps the hierarchy and the AGVS state, so that a rerun with the same scene and "
                   "settings skips the hierarchy and continues sampling (e.g. with a smaller --pixel-error)"));
  t.push_back(number("--checkpoint", FIELD(bound.checkpoint_seconds), non_negative(),
                     "With --work: save the AGVS state this often, in seconds, so that a bake cut off continues from "
                     "there when run again (0: only at the end)",
                     true));
  t.push_back(number("--measured-error", FIELD(bound.measured_error), non_negative(),
                     "Stop AGVS once cameras measure at most this many wrong pixels per 1024x1024 frame (mean over the "
                     "cameras), instead of trusting the estimate: measured after one batch and at every doubling of "
                     "the samples (a run may sample up to twice what it needed; --time and the other limits still "
                     "apply)"));
  t.push_back(text("--holes", FIELD(holes),
                   "Stop AGVS once at most this percentage of the measuring cameras' frames shows any wrong pixel "
                   "(e.g. 1%): the holes a player sees. Measured after one batch and at every doubling of the samples "
                   "(by default 1,000 cameras of 1024x768, placed as `viewcells measure` places them), each "
                   "measurement logged with an estimate of the time left; with --measured-error both must hold; "
                   "--time still bounds the bake"));
  t.push_back(whole("--frame-samples", FIELD(bound.frame_samples), 0, 100000,
                    "After AGVS, frames as a sampler: this many cameras per view cell on average, placed as measuring "
                    "cameras are (on a Quake 3 map player eyes, pitch within 30 degrees) but from a seed of their own, "
                    "render --frame-size frames, and every object a frame shows joins its cell's PVS (0: none)"));
  t.push_back(text("--frame-size", FIELD(frame_size), "Frames of --frame-samples, WIDTHxHEIGHT", true));
  t.push_back(whole("--frame-rounds", FIELD(bound.frame_rounds), 1, 64,
                    "Rounds of --frame-samples: after the first, only the cells whose frames still added an object "
                    "get about as many frames again",
                    true));
  t.push_back(whole("--near-samples", FIELD(bound.near.rays_per_object), 0, 4096,
                    "After AGVS, near-object samples: every view cell tests each object whose box lies within "
                    "--near-distance of an object of its PVS and that it lacks, with this many rays from its "
                    "viewpoints (placed as measuring cameras are, --near-eyes a cell on average, a seed of their own) "
                    "to random points on the object; the object joins the PVS when a ray reaches it unblocked. They "
                    "close most of the holes AGVS leaves (trims and steps beside what a cell sees) for a few percent "
                    "of render cost; at most 2^31 rays in all (fewer a candidate on scenes with more). 0: none",
                    true));
  t.push_back(flag("--conservative", FIELD(bound.conservative),
                   "Ship no holes by construction: prove objects hidden through the scene's solid space (a Quake 3 "
                   "map's BSP portals, or a mesh's closed convex solids), and add every (cell, object) pair that is "
                   "neither seen by a ray nor proven hidden to the PVSs, so that no line from any point of a cell "
                   "reaches an object missing from its PVS. Costs more to render than the sampled PVSs (the report's "
                   "hidden.cost_per_frame gives both bounds); an error on a scene that can prove nothing hidden"));
  BakeOption prove = flag("--prove-hidden", FIELD(bound.prove_hidden),
                          "Sort every (cell, object) pair into proven visible, proven hidden and undecided, and report "
                          "the classes and the render cost of both bounds (the report's \"hidden\"); the PVSs written "
                          "are unchanged unless --conservative",
                          "--no-prove-hidden");
  prove.show_default = true;
  t.push_back(prove);
  t.push_back(whole("--proof-steps", FIELD(bound.hidden_max_steps), 1, 1000000000,
                    "Portals one flood of the proof may try; a flood over it keeps all it might still reach (never "
                    "less: only the bound loosens)",
                    true));
  t.push_back(whole("--aimed-rays", FIELD(bound.aimed_rays), 0, 1000000,
                    "With the proof (--prove-hidden, --conservative): rays aimed at each (view cell, object) pair it "
                    "leaves undecided, from points of the cell's empty space to points of the object, up to this many "
                    "a pair; one that arrives proves the pair visible (0: none)",
                    true));
  t.push_back(whole("--near-rounds", FIELD(bound.near.rounds), 1, 64,
                    "Rounds of --near-samples: each round tests the neighbours of what the last one added", true));
  t.push_back(whole("--near-eyes", FIELD(bound.near_eyes), 1, 100000,
                    "Viewpoints a cell has on average for --near-samples", true));
  t.push_back(number("--near-distance", FIELD(bound.near.distance), non_negative(),
                     "Objects are neighbours for --near-samples when their boxes are at most this far apart (default "
                     "1/1000 of the scene's bounding box diagonal)"));
  t.push_back(text("--measure-size", FIELD(measure_size),
                   "Frames of the measuring cameras, WIDTHxHEIGHT (default 1024x768 with --holes, else 64x48)"));
  t.push_back(whole("--measure-cameras", FIELD(bound.measure_cameras), 1, 1'000'000,
                    "Cameras that measure the PVSs, placed and counted as `viewcells measure` does (on a Quake 3 map "
                    "player eyes above floors reachable from the spawn points, else random points of the view box; "
                    "64x48 pixels, seed 1): the report gives the written file's measured pixel error (default: 5000 "
                    "with --measured-error, else none)"));
  // Where players stand on scenes other than Quake 3 maps (also build's, measure's, play-space's).
  const std::string g = "Play space from floors (scenes other than Quake 3 maps)";
  t.push_back(in_group(number("--metres-per-unit", FIELD(sampling.floors.config.metres_per_unit), positive(),
                              "Metres in one unit of the scene (default: the file's own: 1 for glTF, 1/32 for a Quake "
                              "3 map; 1 when the file does not say, e.g. OBJ)"),
                       g));
  BakeOption start;  // repeatable: each value is one more start point
  start.flag = "--start";
  start.kind = Kind::kTexts;
  start.help = "Where players start, X,Y,Z in scene units (repeatable; default: the file's spawn nodes, else every "
               "floor region of at least --min-region)";
  start.check = [](const std::string&) { return std::string(); };
  start.set = [](BakeOptions& b, const std::string& xyz) { b.sampling.floors.starts.push_back(xyz); };
  start.show = [](const BakeOptions&) { return std::string(); };
  t.push_back(in_group(start, g));
  t.push_back(in_group(flag("--only-from-starts", FIELD(sampling.floors.config.only_from_starts),
                            "With start points: only what they reach (default: also every floor region of at least "
                            "--min-region within --region-margin of it, since walking misses jump pads and "
                            "teleporters)"),
                       g));
  t.push_back(in_group(number("--region-margin", FIELD(sampling.floors.config.region_margin), non_negative(),
                              "With start points: floor regions join within this many metres (horizontally) of what "
                              "they reach",
                              true),
                       g));
  t.push_back(in_group(number("--player-height", FIELD(sampling.floors.config.player_height), positive(),
                              "Free space a standing player needs above a floor, metres", true),
                       g));
  t.push_back(in_group(number("--step", FIELD(sampling.floors.config.step), non_negative(),
                              "Highest step a player walks up, metres", true),
                       g));
  t.push_back(in_group(text("--eye-band", FIELD(sampling.floors.eye_band),
                            "Eye heights above a floor, LO,HI metres (crouch to jump; default 1,3)"),
                       g));
  t.push_back(in_group(number("--walk-normal", FIELD(sampling.floors.config.walk_normal), in_range(0.01, 1),
                              "Least z of a walkable floor's unit normal (0.7: 45.6 degrees)", true),
                       g));
  t.push_back(in_group(number("--floor-cell", FIELD(sampling.floors.config.cell), in_range(0.01, 100),
                              "Spacing of the columns of rays that find the floors, metres", true),
                       g));
  t.push_back(in_group(number("--min-region", FIELD(sampling.floors.config.min_region), non_negative(),
                              "Floor regions at least this large are starts (with start points too, unless "
                              "--only-from-starts), square metres",
                              true),
                       g));
  for (BakeOption& o : t) {
    o.keyword = o.flag.substr(2);
    std::replace(o.keyword.begin(), o.keyword.end(), '-', '_');
  }
  return t;
}

#undef FIELD

}  // namespace

const std::vector<BakeOption>& bake_option_table() {
  static const std::vector<BakeOption> table = make_table();
  return table;
}

const BakeOption* find_bake_option(const std::string& name) {
  for (const BakeOption& o : bake_option_table())
    if (o.flag == name || o.keyword == name || (!o.negation.empty() && o.negation == name)) return &o;
  return nullptr;
}

void set_bake_option(BakeOptions& options, const BakeOption& option, const std::string& text, const std::string& name) {
  if (text.empty() && option.kind != Kind::kFlag)
    throw Error(name + " was given an empty value: give a value or leave the option out");
  const std::string why = option.check(text);
  if (!why.empty()) throw Error(name + ": " + why);
  option.set(options, text);
  options.given.insert(option.flag);
}

std::string bake_options_listing() {
  std::string out;
  for (const BakeOption& o : bake_option_table()) {
    std::string head = "  " + o.flag;
    if (!o.negation.empty()) head += ", " + o.negation;
    if (o.kind != Kind::kFlag) head += " " + (o.type.empty() ? std::string("TEXT") : o.type);
    out += head + "\n      " + o.help + "\n";
  }
  return out;
}

std::string rename_options(std::string message, std::vector<std::pair<std::string, std::string>> names) {
  // Longer flags first, so that none is taken for a part of another.
  std::sort(names.begin(), names.end(), [](const auto& x, const auto& y) { return x.first.size() > y.first.size(); });
  auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_'; };
  for (const auto& [flag, name] : names)
    for (size_t at = message.find(flag); at != std::string::npos; at = message.find(flag, at)) {
      const size_t end = at + flag.size();
      if ((end < message.size() && word(message[end])) || (at > 0 && word(message[at - 1]))) {
        at = end;
        continue;
      }
      message.replace(at, flag.size(), name);
      at += name.size();
    }
  return message;
}

BakeOptions parse_bake_words(const std::vector<std::string>& words) {
  BakeOptions options;
  bool scene = false;
  for (size_t i = 0; i < words.size(); ++i) {
    const std::string& word = words[i];
    if (word == "-o" || word == "--output" || word.rfind("--output=", 0) == 0) {
      const size_t eq = word.find('=');
      if (eq == std::string::npos && i + 1 == words.size()) throw Error(word + " needs a value");
      options.bound.output = eq == std::string::npos ? words[++i] : word.substr(eq + 1);
      if (options.bound.output.empty()) throw Error("--output was given an empty value: give a file");
      continue;
    }
    if (word.rfind("-", 0) != 0 || word == "-") {
      if (scene) throw Error("bake: '" + word + "' is a second scene (options start with --)");
      options.sampling.scene = word;
      scene = true;
      continue;
    }
    const size_t eq = word.find('=');
    const std::string name = word.substr(0, eq);
    if (name == "--help" || name == "-h")
      throw Error("bake: help is not an option of a bake from code; the options are viewcells bake's:\n" +
                  bake_options_listing());
    const BakeOption* option = find_bake_option(name);
    if (!option || name.rfind("--", 0) != 0)
      throw Error("bake: unknown option " + name + " (the options are those of `viewcells bake --help`)");
    if (option->kind == Kind::kFlag) {
      const bool negated = name == option->negation;
      std::string value = eq == std::string::npos ? "true" : word.substr(eq + 1);
      if (negated) value = value == "true" ? "false" : (value == "false" ? "true" : value);
      set_bake_option(options, *option, value, name);
      continue;
    }
    if (eq == std::string::npos && i + 1 == words.size()) throw Error(name + " needs a value");
    const std::string value = eq == std::string::npos ? words[++i] : word.substr(eq + 1);
    if (option->kind != Kind::kTexts && options.given.count(option->flag))
      throw Error(name + " was given twice");
    set_bake_option(options, *option, value, name);
  }
  if (!scene) throw Error("bake: no scene given");
  if (options.bound.output.empty()) throw Error("bake: no output given (-o FILE)");
  return options;
}

}  // namespace viewcells::pipeline
