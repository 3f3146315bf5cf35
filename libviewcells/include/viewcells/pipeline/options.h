#pragma once
// The bake's options as a person states them, and the one table that names them.
//
// `viewcells bake`'s flags (--max-cells), Python's keywords (max_cells) and vc_bake's words all
// set the fields of BakeOptions through bake_option_table(): each option's name, help, check and
// the field it sets are written once, here. BakeOptions::config() turns the options into the
// BakeConfig the library runs (sizes, bytes, percentages, boxes and start points parsed; the
// defaults that depend on the scene are pipeline::resolve()'s). The structs that other commands
// share (sampling, floors, cells, merge) are here too, with the text parsers they use.
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "viewcells/agvs/agvs.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/sampling.h"
#include "viewcells/viewspace/floor_space.h"

namespace viewcells::pipeline {

constexpr uint64_t kMaxSamples = uint64_t{1} << 40;  // a trillion rays: beyond any one machine's memory
constexpr uint64_t kMaxCells = 10'000'000;

/// "WIDTHxHEIGHT" of option `option`, each a whole number from 1 to `max`; Error otherwise.
std::pair<uint32_t, uint32_t> parse_size(const std::string& text, const std::string& option, uint32_t max);
/// Comma-separated numbers of option `option`; throws Error naming the option.
std::vector<double> parse_numbers(const std::string& text, const std::string& option);
/// "xmin,ymin,zmin,xmax,ymax,zmax" with min < max on every axis.
Box3 parse_box(const std::string& text);
/// "123", "64K", "2M", "1G" (powers of 1024) -> bytes.
uint64_t parse_bytes(const std::string& text);
/// "1%" or "1" (percent) -> 0.01; above 0 and at most 100.
double parse_percent(const std::string& text, const std::string& option);
std::vector<std::string> split_list(const std::string& text);

/// A check of an option's text: "" when it is a value the option takes, else why not
/// ("'x' is not allowed: give a whole number from 1 to 10").
using OptionCheck = std::function<std::string(const std::string& text)>;
/// A check and how help names what it takes ("INT in [1, 10]", "NUMBER > 0"; "" any text): the
/// table's options and the command line's own options share these.
struct ValueRule {
  OptionCheck check;
  std::string type;
};
/// A whole number from lo to hi, written without sign or exponent.
ValueRule whole_rule(uint64_t lo, uint64_t hi);
/// A finite number, any (what takes it checks its own range).
ValueRule any_number_rule();
ValueRule positive_rule();
ValueRule non_negative_rule();
ValueRule range_rule(double lo, double hi);
/// "'TEXT' is not allowed: give WANTED".
std::string refused_value(const std::string& text, const std::string& wanted);
/// A number as help shows it (1e-06, 0.25, 100).
std::string option_number(double v);

/// Where players stand on a scene without a view space of its own (viewspace/floor_space.h).
struct FloorOptions {
  FloorSpaceConfig config;  ///< the defaults, overwritten by the options given
  std::string eye_band;     ///< "LO,HI" in metres
  std::vector<std::string> starts;  ///< "X,Y,Z" each, in scene units
  /// The config with eye_band and starts parsed (Error naming the option when malformed).
  FloorSpaceConfig floors() const;
};

/// The scene and its sampling (sample, build, compare, bake).
struct SamplingOptions {
  std::string scene;
  std::string objects = "auto";
  uint64_t samples = 1'000'000;
  uint64_t segments = 0;
  uint64_t seed = 1;
  std::string view_box;
  std::string empty_space = "auto";
  bool fast = false;
  int max_recasts = 8;
  FloorOptions floors;

  SceneSource source() const;
  SamplerConfig sampler(bool quiet) const;
};

/// Render cost model and subdivision (build, bake).
struct CellOptions {
  uint32_t max_cells = 1000;
  bool no_ga = false, ga = false;
  uint32_t ga_candidates = 150;
  uint32_t axis_candidates = 200;
  bool exact_candidates = false;
  double min_reduction = 1e-6;
  double cost_a = 100, cost_b = 1, cost_c = 0;
  std::string screen = "1024x768";
  double fov = 90;
  std::string density_band;
  bool play_space = false, no_play_space = false;

  CostModel model() const;
  /// Seeded from the sampling options' seed.
  SubdivisionConfig subdivision(bool quiet, const SamplingOptions& s) const;
};

/// What merging decides on: the leaves' PVSs from the construction samples alone, or united
/// with AGVS's (build, compare, bake).
struct MergeOptions {
  std::string pvs = "agvs";
  uint64_t samples = 0;
  double pixel_error = 0;
  uint32_t lanes = 1;
  /// Unset for pvs "samples"; else AGVS with the stopping rule given (default: as many samples
  /// as the construction had, `construction_samples`), seeded from `seed`.
  std::optional<AgvsConfig> agvs(bool quiet, uint64_t seed, uint64_t construction_samples) const;
};

/// Every option of a bake, as `viewcells bake` defaults them. Set through the table (set_option,
/// parse_bake_words), which also records what was given.
struct BakeOptions {
  BakeConfig bound;  ///< the options that are a field of the bake's config
  SamplingOptions sampling;
  CellOptions cells;
  MergeOptions merge;
  AgvsConfig agvs;  ///< the PVSs' AGVS: pixel error, time, samples, batch, lanes, share
  std::string memory, memory_of = "file";
  std::string holes, measure_size, frame_size = "256x192";
  std::set<std::string> given;  ///< flags given ("--cells"), for the checks of what excludes what

  BakeOptions();
  /// The bake these options ask for; Error naming the option when a value or a combination is
  /// refused (a budget is needed: cells or memory).
  BakeConfig config(bool quiet) const;
};

/// One option of the bake.
struct BakeOption {
  enum class Kind { kFlag, kWhole, kNumber, kText, kTexts };
  std::string flag;         ///< "--max-cells"; a flag may have a negation ("--no-prove-hidden")
  std::string negation;     ///< "--no-prove-hidden", or empty
  std::string keyword;      ///< "max_cells": the flag without its dashes, '-' as '_'
  Kind kind = Kind::kText;
  std::string type;         ///< what a value must be, for help: "INT in [1, 10000000]", "NUMBER > 0", "{a,b}"; "" any text
  std::string help;
  std::string group;        ///< help's heading ("Budget")
  bool show_default = false;
  std::vector<std::string> excludes;  ///< flags it may not be given with
  OptionCheck check;
  std::function<void(BakeOptions&, const std::string& text)> set;
  /// The default as help shows it, from a BakeOptions{}.
  std::function<std::string(const BakeOptions&)> show;
};

/// The bake's options, in the order `viewcells bake --help` lists them (but the scene, -o and
/// --report, which each front end takes its own way).
const std::vector<BakeOption>& bake_option_table();
/// The option with this flag ("--cells") or keyword ("cells"), or nullptr.
const BakeOption* find_bake_option(const std::string& name);
/// Sets one option from its text ("true"/"false" for a flag); Error "NAME: why" when refused,
/// with NAME as the caller calls it (a flag, a keyword).
void set_bake_option(BakeOptions& options, const BakeOption& option, const std::string& text, const std::string& name);
/// `viewcells bake`'s words after "bake" (the scene, -o FILE, --flag, --option VALUE or
/// --option=VALUE) as options, with the command line's checks: what vc_bake parses. --report
/// is no option of a bake from code; --help is an error listing the options.
BakeOptions parse_bake_words(const std::vector<std::string>& words);
/// A listing of the options (flag, value, help), for errors that list them.
std::string bake_options_listing();
/// `message` with every whole flag of `names` ({"--max-cells", "max_cells (keyword)"}) replaced
/// by its name there: a binding's words for the options the library's messages name.
std::string rename_options(std::string message, std::vector<std::pair<std::string, std::string>> names);

}  // namespace viewcells::pipeline
