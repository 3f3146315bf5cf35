// The evaluator's walk alone, on a built hierarchy: draws SAMPLES random samples (seed 7) in
// the file's view box and times evaluation_pvs (every leaf each segment has length in, and the
// objects at its ends) on them, repeated; prints each run's seconds and a checksum of the lists,
// so that two builds can be compared on the same input (the validated merge walks its held-out
// samples this way, and `compare` its evaluation sets).
// Usage: viewcells_eval_bench SCENE FILE.vcells [SAMPLES] [REPEATS] [THREADS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "viewcells/bsp/subdivision.h"
#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/eval/evaluate.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/q3/bsp_file.h"

int main(int argc, char** argv) {
  viewcells::register_q3_map_format();
  using Clock = std::chrono::steady_clock;
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SCENE FILE.vcells [SAMPLES] [REPEATS] [THREADS]\n", argv[0]);
    return 2;
  }
  try {
    const uint64_t samples = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 4'000'000;
    const int repeats = argc > 4 ? std::max(1, std::atoi(argv[4])) : 3;
    const int threads = argc > 5 ? std::max(1, std::atoi(argv[5])) : 0;
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    const viewcells::Scene scene = viewcells::load_scene(argv[1]);
    const viewcells::SubdivisionFile file = viewcells::read_subdivision(argv[2]);
    const auto caster = viewcells::make_embree_caster(scene);
    viewcells::SamplerConfig sc;
    sc.samples = samples;
    sc.seed = 7;
    sc.view_box = file.subdivision.view_box;
    sc.show_progress = false;
    const viewcells::SamplingResult r = viewcells::sample_segments(scene, *caster, sc);
    double best = 1e300;
    for (int k = 0; k < repeats; ++k) {
      const auto t0 = Clock::now();
      const std::vector<std::vector<uint32_t>> pvs = viewcells::evaluation_pvs(file.subdivision, r.segments);
      const double s = std::chrono::duration<double>(Clock::now() - t0).count();
      best = std::min(best, s);
      uint64_t entries = 0, check = 0;
      for (size_t n = 0; n < pvs.size(); ++n)
        for (uint32_t o : pvs[n]) {
          ++entries;
          check = check * 1000003 + n * 8191 + o;
        }
      std::printf("run %d: %zu leaves' nodes, %zu segments, %.3f s, %llu entries, checksum %016llx\n", k,
                  pvs.size(), r.segments.size(), s, static_cast<unsigned long long>(entries),
                  static_cast<unsigned long long>(check));
    }
    std::printf("fastest: %.3f s\n", best);
  } catch (const viewcells::Error& e) {
    std::fprintf(stderr, "eval_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
