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

namespace {

CLI::Validator validator(const pipeline::ValueRule& rule) {
  return CLI::Validator([check = rule.check](std::string& text) { return check(text); }, rule.type);
}

}  // namespace

CLI::Validator whole(uint64_t lo, uint64_t hi) { return validator(pipeline::whole_rule(lo, hi)); }
CLI::Validator positive() { return validator(pipeline::positive_rule()); }
CLI::Validator non_negative() { return validator(pipeline::non_negative_rule()); }
CLI::Validator in_range(double lo, double hi) { return validator(pipeline::range_rule(lo, hi)); }

CLI::Validator table_check(const pipeline::BakeOption& o) { return validator({o.check, o.type}); }

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

void add_floor_options(CLI::App* cmd, FloorOptions& a) {
  FloorSpaceConfig& c = a.config;
  add_shared_option(cmd, "--metres-per-unit", c.metres_per_unit);
  add_shared_option(cmd, "--start", a.starts);
  add_shared_option(cmd, "--only-from-starts", c.only_from_starts);
  add_shared_option(cmd, "--region-margin", c.region_margin);
  add_shared_option(cmd, "--player-height", c.player_height);
  add_shared_option(cmd, "--step", c.step);
  add_shared_option(cmd, "--eye-band", a.eye_band);
  add_shared_option(cmd, "--walk-normal", c.walk_normal);
  add_shared_option(cmd, "--floor-cell", c.cell);
  add_shared_option(cmd, "--min-region", c.min_region);
}

void add_sampling_options(CLI::App* cmd, SamplingOptions& a) {
  cmd->add_option("scene", a.scene, "Scene file (.obj, .ply, .off, .stl, or a Quake 3 .bsp)")->required();
  auto* samples = add_shared_option(cmd, "--samples", a.samples);
  add_shared_option(cmd, "--segments", a.segments)->excludes(samples);
  add_shared_option(cmd, "--seed", a.seed);
  add_shared_option(cmd, "--objects", a.objects);
  add_shared_option(cmd, "--view-box", a.view_box);
  add_shared_option(cmd, "--empty-space", a.empty_space);
  add_shared_option(cmd, "--max-recasts", a.max_recasts);
  add_shared_option(cmd, "--fast", a.fast);
}

void add_merge_options(CLI::App* cmd, MergeOptions& a) {
  add_shared_option(cmd, "--merge-pvs", a.pvs);
  add_shared_option(cmd, "--merge-samples", a.samples);
  add_shared_option(cmd, "--merge-pixel-error", a.pixel_error);
  add_shared_option(cmd, "--merge-mutation-lanes", a.lanes);
}

void add_cell_options(CLI::App* cmd, CellOptions& a, const std::string& max_cells_help, bool no_play_space) {
  if (!max_cells_help.empty())
    cmd->add_option("--max-cells", a.max_cells, max_cells_help)
        ->capture_default_str()
        ->check(table_check(*pipeline::find_bake_option("--max-cells")));
  auto* no_ga = add_shared_option(cmd, "--no-ga", a.no_ga);
  add_shared_option(cmd, "--ga", a.ga)->excludes(no_ga);
  add_shared_option(cmd, "--ga-candidates", a.ga_candidates);
  add_shared_option(cmd, "--axis-candidates", a.axis_candidates);
  add_shared_option(cmd, "--exact-candidates", a.exact_candidates);
  add_shared_option(cmd, "--min-reduction", a.min_reduction);
  add_shared_option(cmd, "--cost-a", a.cost_a);
  add_shared_option(cmd, "--cost-b", a.cost_b);
  add_shared_option(cmd, "--cost-c", a.cost_c);
  add_shared_option(cmd, "--screen", a.screen);
  add_shared_option(cmd, "--fov", a.fov);
  add_shared_option(cmd, "--density-band", a.density_band);
  auto* play = add_shared_option(cmd, "--play-space", a.play_space);
  if (no_play_space) add_shared_option(cmd, "--no-play-space", a.no_play_space)->excludes(play);
}

void add_bake_options(CLI::App* cmd, pipeline::BakeOptions& into) {
  using Kind = pipeline::BakeOption::Kind;
  for (const pipeline::BakeOption& o : pipeline::bake_option_table()) {
    // The table's entries live as long as the process; `into` as long as the command.
    auto set = [&o, &into](const std::string& text) {
      try {
        pipeline::set_bake_option(into, o, text, o.flag);
      } catch (const Error& e) {
        throw CLI::ValidationError(e.what());
      }
    };
    CLI::Option* opt = nullptr;
    if (o.kind == Kind::kFlag) {
      opt = cmd->add_flag_function(o.flag + (o.negation.empty() ? "" : ",!" + o.negation),
                                   [set](int64_t count) { set(count > 0 ? "true" : "false"); }, o.help);
    } else {
      opt = cmd->add_option(
          o.flag,
          [set](const CLI::results_t& values) {
            for (const std::string& v : values) set(v);
            return true;
          },
          o.help);
      opt->type_name(o.kind == Kind::kWhole ? "UINT" : o.kind == Kind::kNumber ? "FLOAT" : "TEXT")->check(table_check(o));
      if (o.kind == Kind::kTexts) opt->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
      if (o.show_default) opt->default_str(o.show(pipeline::BakeOptions{}));
    }
    if (!o.group.empty()) opt->group(o.group);
  }
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
