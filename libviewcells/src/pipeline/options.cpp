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

std::string refused_value(const std::string& text, const std::string& wanted) {
  return "'" + text + "' is not allowed: give " + wanted;
}

std::string option_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

ValueRule whole_rule(uint64_t lo, uint64_t hi) {
  const std::string range = std::to_string(lo) + " to " + std::to_string(hi);
  return {[lo, hi, range](const std::string& text) -> std::string {
            uint64_t v = 0;
            const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < lo || v > hi)
              return refused_value(text, "a whole number from " + range);
            return "";
          },
          "INT in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]"};
}

namespace {

/// One finite number that `ok` accepts; `wanted` completes "give ...".
OptionCheck number_check(std::function<bool(double)> ok, const std::string& wanted) {
  return [ok, wanted](const std::string& text) -> std::string {
    try {
      size_t used = 0;
      const double v = std::stod(text, &used);
      if (used == text.size() && std::isfinite(v) && ok(v)) return "";
    } catch (const std::exception&) {
    }
    return refused_value(text, wanted);
  };
}

}  // namespace

ValueRule any_number_rule() { return {number_check([](double) { return true; }, "a finite number"), ""}; }
ValueRule positive_rule() { return {number_check([](double v) { return v > 0; }, "a number above 0"), "NUMBER > 0"}; }
ValueRule non_negative_rule() {
  return {number_check([](double v) { return v >= 0; }, "a number of at least 0"), "NUMBER >= 0"};
}
ValueRule range_rule(double lo, double hi) {
  return {number_check([lo, hi](double v) { return v >= lo && v <= hi; },
                       "a number from " + option_number(lo) + " to " + option_number(hi)),
          "NUMBER in [" + option_number(lo) + ", " + option_number(hi) + "]"};
}

const BakeOption* find_bake_option(const std::string& name) {
  for (const BakeOption& o : bake_option_table())
    if (o.flag == name || o.keyword == name || (!o.negation.empty() && o.negation == name)) return &o;
  return nullptr;
}

void set_bake_option(BakeOptions& options, const BakeOption& option, const std::string& text, const std::string& name) {
  if (text.empty() && option.kind != BakeOption::Kind::kFlag)
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
    if (o.kind != BakeOption::Kind::kFlag) head += " " + (o.type.empty() ? std::string("TEXT") : o.type);
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
    if (option->kind == BakeOption::Kind::kFlag) {
      std::string value = eq == std::string::npos ? "true" : word.substr(eq + 1);
      if (name == option->negation) {  // --no-x=1 is --x=false; what is no truth value stays, refused
        if (value == "true" || value == "1" || value == "on" || value == "yes") value = "false";
        else if (value == "false" || value == "0" || value == "off" || value == "no") value = "true";
      }
      set_bake_option(options, *option, value, name);
      continue;
    }
    if (eq == std::string::npos && i + 1 == words.size()) throw Error(name + " needs a value");
    const std::string value = eq == std::string::npos ? words[++i] : word.substr(eq + 1);
    if (option->kind != BakeOption::Kind::kTexts && options.given.count(option->flag))
      throw Error(name + " was given twice");
    set_bake_option(options, *option, value, name);
  }
  if (!scene) throw Error("bake: no scene given");
  if (options.bound.output.empty()) throw Error("bake: no output given (-o FILE)");
  return options;
}

}  // namespace viewcells::pipeline
