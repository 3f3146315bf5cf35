// compare: view cells by several methods, scored on independent samples.
#include <memory>

#include "options.h"
#include "viewcells/core/parallel.h"
#include "viewcells/q3/level.h"
#include "viewcells/studies/compare.h"

namespace viewcells::cli {

namespace {

/// `compare`'s options: those that are a field of the run's config bind to `bound`; the scene,
/// sampling and merge options are shared with other commands, and the method list and the cell
/// count have defaults that depend on the scene (decided when the command runs).
struct CompareArgs {
  studies::CompareRunConfig bound;
  SamplingOptions sampling;
  std::string methods = "av-m,av-m-samples,av-s,kd-casm,kd-lasm,kd-vt,kd-vt-star,bsp";
  bool methods_given = false;
  uint32_t max_cells = 1000;
  bool max_cells_given = false;
  MergeOptions merge;
};

int run_compare(const CompareArgs& a, const Common& c) {
  check_files({a.sampling.scene}, {}, {a.bound.output_dir});
  ThreadLimit threads(c.threads);
  studies::CompareRunConfig config = a.bound;
  config.scene = a.sampling.source();
  if (a.methods_given || !is_q3_map(a.sampling.scene)) config.methods = split_list(a.methods);
  config.max_cells = a.max_cells_given ? a.max_cells : 0;
  config.construction = a.sampling.sampler(c.quiet);
  config.merge_agvs = a.merge.agvs(c.quiet, config.construction.seed, config.construction.samples);
  studies::compare(config, c.logger());
  return 0;
}

}  // namespace

void add_compare_command(CLI::App& app, const Common& common, Commands& commands) {
  auto a = std::make_shared<CompareArgs>();
  auto* cm = app.add_subcommand("compare",
                                "Build view cells with several methods from the same samples and score them all on "
                                "independent evaluation samples (paper, section 6)");
  add_sampling_options(cm, a->sampling);
  cm->add_option("--methods", a->methods,
                 "Comma-separated: av-m (AV-S's cells merged; see --merge-pvs), av-m-samples (greedy merging on the construction samples' PVSs alone, the paper's AV-M), av-s, av-s-exact (AV-S with --exact-candidates, to compare the two in one run), kd-casm, kd-lasm, kd-vt, kd-vt-star, bsp, and q3-clusters (the clusters "
                 "q3map2 compiled into a Quake 3 map; the default on a .bsp with visibility data, with av-m,av-s,kd-casm)")
      ->capture_default_str()
      ->each([a](const std::string&) { a->methods_given = true; });
  cm->add_option("--max-cells", a->max_cells, "Cells per method at most (on a Quake 3 map: 3 x its clusters)")
      ->capture_default_str()
      ->check(positive())
      ->each([a](const std::string&) { a->max_cells_given = true; });
  cm->add_option("--eval-samples", a->bound.evaluation_samples, "Evaluation samples (default: 4 x --samples)")
      ->check(whole(1, kMaxSamples));
  cm->add_option("--eval-seed", a->bound.evaluation_seed, "Evaluation seed (default: --seed + 1000003)");
  cm->add_option("--eval-sets", a->bound.evaluation_sets,
                 "Independent evaluation sets, each of --eval-samples (set K has seed --eval-seed + K - 1); every "
                 "method is scored on each, in curves.csv's cost and cost_2, cost_3, ... columns. Their "
                 "disagreement is the evaluator's own noise")
      ->capture_default_str()
      ->check(whole(1, 16));
  cm->add_option("--histogram-cells", a->bound.histogram_cells, "Cell count of the cost histograms (default: --max-cells)");
  cm->add_option("--cost-a", a->bound.model.a, "Render cost model: minimum cost of an object")->capture_default_str();
  cm->add_option("--cost-b", a->bound.model.b, "Render cost model: cost per triangle")->capture_default_str();
  cm->add_flag("--no-ga", a->bound.geometry_aligned_off, "AV-S/AV-M without geometry-aligned candidates");
  cm->add_option("--axis-candidates", a->bound.subdivision.max_axis_candidates, "AV-S/AV-M: axis-aligned positions per axis and cell")
      ->capture_default_str()
      ->check(positive());
  cm->add_flag("--exact-candidates", a->bound.subdivision.exact_candidates, "AV-S/AV-M: " + pipeline::find_bake_option("--exact-candidates")->help);
  cm->add_option("--min-reduction", a->bound.subdivision.min_reduction,
                 "AV-S/AV-M: stop when splits reduce the cost by less than this share of the initial cost for 50 "
                 "splits running (0: always reach --max-cells)")
      ->capture_default_str()
      ->check(non_negative());
  cm->add_option("--ga-candidates", a->bound.subdivision.ga_candidates, "AV-S/AV-M: geometry-aligned planes per cell")
      ->capture_default_str()
      ->check(positive());
  add_merge_options(cm, a->merge);
  cm->add_option("-o,--output", a->bound.output_dir, "Directory for curves.csv, histogram.csv, summary.json")->required();
  commands.push_back({cm, [a, &common] { return run_compare(*a, common); }});
}

}  // namespace viewcells::cli
