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
#include "viewcells/pipeline/options.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/pipeline/sampling.h"

namespace viewcells::cli {

using pipeline::kMaxCells;
using pipeline::kMaxSamples;
using pipeline::parse_box;
using pipeline::parse_bytes;
using pipeline::parse_numbers;
using pipeline::parse_size;
using pipeline::split_list;
using pipeline::FloorOptions;
using pipeline::SamplingOptions;
using pipeline::CellOptions;
using pipeline::MergeOptions;

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

/// Before any work: refuses an output that is also an input or another output, that exists as
/// something other than a regular file, or whose directory is missing. `directories` are outputs
/// that are directories (a work directory, a web page's): they may exist as directories, not as
/// anything else, and are no other input or output. Empty names are options not given.
void check_files(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                 const std::vector<std::string>& directories = {});
/// Refuses an option given with an empty value (`-o ""`): no option of viewcells takes one.
void check_no_empty_values(const CLI::App& command);

/// The options other commands share with bake, from bake's table (pipeline/options.h: help,
/// checks and defaults written once), bound to the fields of the shared structs.
void add_floor_options(CLI::App* cmd, FloorOptions& a);
void add_sampling_options(CLI::App* cmd, SamplingOptions& a);
/// `max_cells_help` empty: no --max-cells option; `no_play_space`: also --no-play-space.
void add_cell_options(CLI::App* cmd, CellOptions& a, const std::string& max_cells_help, bool no_play_space = false);
void add_merge_options(CLI::App* cmd, MergeOptions& a);
/// An option of bake's table on another command, bound to `field` (a flag: a bool).
template <class T>
CLI::Option* add_shared_option(CLI::App* cmd, const std::string& flag, T& field);
/// Every option of bake's table, setting `into` (pipeline::set_bake_option).
void add_bake_options(CLI::App* cmd, pipeline::BakeOptions& into);
/// The table's check of one option as CLI11's validator.
CLI::Validator table_check(const pipeline::BakeOption& o);

template <class T>
CLI::Option* add_shared_option(CLI::App* cmd, const std::string& flag, T& field) {
  const pipeline::BakeOption& o = *pipeline::find_bake_option(flag);
  CLI::Option* opt = nullptr;
  if constexpr (std::is_same_v<T, bool>) {
    opt = cmd->add_flag(flag, field, o.help);
  } else {
    opt = cmd->add_option(flag, field, o.help)->check(table_check(o));
    if (o.show_default) opt->capture_default_str();
  }
  if (!o.group.empty()) opt->group(o.group);
  return opt;
}

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
