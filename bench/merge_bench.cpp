// The merge stage alone, on a built hierarchy: the neighbour graph (partition_from_subdivision)
// and greedy merging on the file's leaf PVSs (merge_cells), each repeated; prints each run's
// seconds and the merge history's cost at a few counts, so that two builds can be compared on
// the same input without the subdivision before it (scripts/bench.sh merge).
// Usage: viewcells_merge_bench SCENE FILE.vcells [REPEATS] [THREADS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "viewcells/bsp/subdivision.h"
#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/merge/merge.h"
#include "viewcells/q3/bsp_file.h"

int main(int argc, char** argv) {
  viewcells::register_q3_map_format();
  using Clock = std::chrono::steady_clock;
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SCENE FILE.vcells [REPEATS] [THREADS]\n", argv[0]);
    return 2;
  }
  try {
    const int repeats = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
    const int threads = argc > 4 ? std::max(1, std::atoi(argv[4])) : 0;
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    double best_graph = 1e300, best_merge = 1e300;
    const viewcells::Scene scene = viewcells::load_scene(argv[1]);
    viewcells::SubdivisionFile file = viewcells::read_subdivision(argv[2]);
    viewcells::rebuild_cells(file.subdivision);
    for (int r = 0; r < repeats; ++r) {
      std::vector<std::vector<uint32_t>> lists = file.leaf_pvs;  // moved into the partition, as build does
      const auto t0 = Clock::now();
      const viewcells::CellPartition p = viewcells::partition_from_subdivision(file.subdivision, std::move(lists));
      const auto t1 = Clock::now();
      const viewcells::MergeHistory h = viewcells::merge_cells(scene, p, file.cost_model, {});
      const auto t2 = Clock::now();
      best_graph = std::min(best_graph, std::chrono::duration<double>(t1 - t0).count());
      best_merge = std::min(best_merge, std::chrono::duration<double>(t2 - t1).count());
      std::printf("run %d: cells %zu, neighbour graph %.3f s, merge %.3f s, pair costs %llu, cost at 1/10 %.6f\n", r,
                  p.size(), std::chrono::duration<double>(t1 - t0).count(),
                  std::chrono::duration<double>(t2 - t1).count(),
                  static_cast<unsigned long long>(h.stats.evaluations), h.cost_with(std::max<size_t>(1, p.size() / 10)));
    }
    std::printf("fastest: neighbour graph %.3f s, merge %.3f s\n", best_graph, best_merge);
  } catch (const viewcells::Error& e) {
    std::fprintf(stderr, "merge_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
