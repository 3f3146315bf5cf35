#pragma once
// What the subcommands share: global options, option parsers and validators, the scene and
// sampling options, cut rules, and the check of input and output files before any work.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/core/format.h"
#include "viewcells/core/vec3.h"
#include "viewcells/agvs/agvs.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/pipeline/sampling.h"

namespace viewcells::cli {

constexpr uint64_t kMaxSamples = uint64_t{1} << 40;  // a trillion rays: beyond any one machine's memory
constexpr uint64_t kMaxCells = 10'000'000;
/// --exact-candidates, shared by build, bake and compare.
constexpr const char* kExactCandidatesHelp =
    "Axis-aligned positions as the paper draws them: a uniform random subset of the distinct segment-end coordinates "
    "of each cell, which needs them all sorted (about 3x slower subdivision on large scenes). Default: random segment "
    "ends until --axis-candidates distinct ones, so that coordinates where many segments end (walls) are likelier; "
    "both evaluate their positions exactly";

/// Global options.
struct Common {
  int threads = 0;
  bool quiet = false;
  void log(const std::string& s) const;
  /// The pipeline's log: lines on stderr unless --quiet.
  pipeline::Log logger() const;
};

/// Writes the result's JSON report to `path` when one was asked for, and says so (`what`).
template <class Result>
void write_report_to(const std::string& path, const Result& result, const Common& c, const std::string& what = "report") {
  if (path.empty()) return;
  pipeline::write_report(path, result);
  c.log("viewcells: " + what + " -> " + path);
}

/// A subcommand and what runs it once its options are parsed.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
using Commands = std::vector<Command>;

/// A whole number from lo to hi, written without sign or exponent (CLI11 alone reads "-1" into
/// an unsigned option as 2^64 - 1).
CLI::Validator whole(uint64_t lo, uint64_t hi);
/// A finite number above zero.
CLI::Validator positive();
/// A finite number of at least zero.
CLI::Validator non_negative();
/// A finite number from lo to hi (NaN is refused, and the message says the range enforced).
CLI::Validator in_range(double lo, double hi);

/// "WIDTHxHEIGHT" of option `option`, each a whole number from 1 to `max`; Error otherwise.
std::pair<uint32_t, uint32_t> parse_size(const std::string& text, const std::string& option, uint32_t max);
/// Comma-separated numbers of option `option`; throws Error naming the option.
std::vector<double> parse_numbers(const std::string& text, const std::string& option);
Box3 parse_box(const std::string& text);
/// "123", "64K", "2M", "1G" (powers of 1024) -> bytes.
uint64_t parse_bytes(const std::string& text);
std::vector<std::string> split_list(const std::string& text);

/// Before any work: refuses an output that is also an input or another output, that exists as
/// something other than a regular file, or whose directory is missing. `directories` are outputs
/// that are directories (a work directory, a web page's): they may exist as directories, not as
/// anything else, and are no other input or output. Empty names are options not given.
void check_files(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                 const std::vector<std::string>& directories = {});
/// Refuses an option given with an empty value (`-o ""`): no option of viewcells takes one.
void check_no_empty_values(const CLI::App& command);

/// Where players stand on a scene without a view space of its own (viewspace/floor_space.h):
/// units, the player's body and start points, for bake, build, measure and play-space.
struct FloorOptions {
  FloorSpaceConfig config;  ///< the defaults, overwritten by the options given
  std::string eye_band;     ///< "LO,HI" in metres
  std::vector<std::string> starts;  ///< "X,Y,Z" each, in scene units
  /// The config with eye_band and starts parsed (Error naming the option when malformed).
  FloorSpaceConfig floors() const;
};
void add_floor_options(CLI::App* cmd, FloorOptions& a);

/// Scene and sampling options shared by sample, build, compare and bake.
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
  FloorOptions floors;  ///< given with add_floor_options

  pipeline::SceneSource source() const;
  SamplerConfig sampler(const Common& c) const;
};
void add_sampling_options(CLI::App* cmd, SamplingOptions& a);

/// Render cost model and subdivision options shared by build and bake.
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
  /// bake: the play space is on where the scene's view space knows players (a Quake 3 map)
  /// unless --no-play-space, --density-band or --view-box says otherwise
  /// (BakeConfig::play_space_where_known).
  bool play_space_by_default = false;

  CostModel model() const;
  /// The seed from the sampling options.
  SubdivisionConfig subdivision(const Common& c, const SamplingOptions& s) const;
};
/// `max_cells_help` empty: no --max-cells option.
void add_cell_options(CLI::App* cmd, CellOptions& a, const std::string& max_cells_help);

/// What merging decides on: the leaves' PVSs from the construction samples alone, or united
/// with AGVS's (build, compare, bake).
struct MergeOptions {
  std::string pvs = "agvs";
  uint64_t samples = 0;
  double pixel_error = 0;
  uint32_t lanes = 1;
  /// Unset for --merge-pvs samples; else AGVS with the stopping rule given (default: as many
  /// samples as the construction had, `construction_samples`), seeded from `seed`.
  std::optional<AgvsConfig> agvs(const Common& c, uint64_t seed, uint64_t construction_samples) const;
};
void add_merge_options(CLI::App* cmd, MergeOptions& a);

/// --count, --memory, --cost-ratio.
struct CutOptions {
  uint32_t count = 0;
  std::string memory;
  double cost_ratio = 0;
  pipeline::CutRule rule() const;
};
void add_cut_options(CLI::App* app, CutOptions& a);

/// --mesh, --slice-png, --slice-z, --slice-width.
void add_view_options(CLI::App* app, pipeline::ViewsConfig& v, const std::string& mesh_help,
                      const std::string& png_help);

/// The subcommands, by file.
void add_scene_commands(CLI::App& app, const Common& common, Commands& commands);    // generate, info, sample, isa
void add_build_commands(CLI::App& app, const Common& common, Commands& commands);    // build, export
void add_cut_commands(CLI::App& app, const Common& common, Commands& commands);      // extract, compress, query, view
void add_pvs_commands(CLI::App& app, const Common& common, Commands& commands);      // pvs, bake, measure
void add_compare_command(CLI::App& app, const Common& common, Commands& commands);   // compare

}  // namespace viewcells::cli
