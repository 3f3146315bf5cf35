// Point location plus PVS lookup through the runtime reader (runtime/), as an engine does per
// frame: VIEWCELLS_BENCH_PVS names the .pvs file (scripts/bench.sh runtime makes a 50k-cell
// city). Viewpoints are uniform in the view box, drawn once (seed 1); each query locates one
// and reads its cell's visible set.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "viewcells/runtime.hpp"

namespace {

struct Fixture {
  std::unique_ptr<viewcells::runtime::PvsFile> pvs;
  std::unique_ptr<viewcells::runtime::PvsFile> compact;  // the same file, lists kept coded
  std::vector<double> points;  // x, y, z per viewpoint
};

Fixture& fixture() {
  static Fixture f = [] {
    Fixture out;
    const char* path = std::getenv("VIEWCELLS_BENCH_PVS");
    if (!path) {
      std::fprintf(stderr, "runtime_bench: set VIEWCELLS_BENCH_PVS to a .pvs file\n");
      std::exit(2);
    }
    out.pvs = std::make_unique<viewcells::runtime::PvsFile>(path);
    out.compact = std::make_unique<viewcells::runtime::PvsFile>(path, true);
    double lo[3], hi[3];
    vc_pvs_view_box(out.pvs->handle(), lo, hi);
    std::mt19937_64 rng(1);
    const size_t n = 1 << 20;
    out.points.resize(3 * n);
    for (size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        out.points[3 * i + k] = std::uniform_real_distribution<double>(lo[k], hi[k])(rng);
    return out;
  }();
  return f;
}

void counters(benchmark::State& state) {
  const Fixture& f = fixture();
  state.SetItemsProcessed(state.iterations());
  state.counters["cells"] = f.pvs->cell_count();
  state.counters["objects"] = f.pvs->object_count();
  state.counters["memory_MB"] = f.pvs->memory_bytes() / 1e6;
  state.counters["compact_memory_MB"] = f.compact->memory_bytes() / 1e6;
  state.counters["list_MB"] = f.pvs->list_bytes() / 1e6;
  state.counters["compact_list_MB"] = f.compact->list_bytes() / 1e6;
}

void BM_Locate(benchmark::State& state) {
  const Fixture& f = fixture();
  const size_t n = f.points.size() / 3;
  size_t i = 0;
  for (auto _ : state) {
    const double* p = &f.points[3 * i];
    benchmark::DoNotOptimize(f.pvs->locate(p[0], p[1], p[2]));
    i = (i + 1) & (n - 1);
  }
  counters(state);
}

void BM_LocateAndList(benchmark::State& state) {
  const Fixture& f = fixture();
  const size_t n = f.points.size() / 3;
  size_t i = 0, total = 0;
  for (auto _ : state) {
    const double* p = &f.points[3 * i];
    const viewcells::runtime::ObjectList l = f.pvs->objects_at(p[0], p[1], p[2]);
    total += l.size + (l.empty() ? 0 : l.data[l.size - 1]);  // touch the list's last entry
    i = (i + 1) & (n - 1);
  }
  benchmark::DoNotOptimize(total);
  counters(state);
}

/// A viewer walking: steps of 0.2% of the view box's diagonal, turning at random (the
/// fixture's points) and reflected at the box, as frames of a camera are (most steps stay in
/// their cell).
struct Walk {
  double lo[3], hi[3], p[3], d[3] = {1, 0, 0}, step = 0;
  size_t i = 0;

  explicit Walk(const vc_pvs* pvs) {
    vc_pvs_view_box(pvs, lo, hi);
    step = 0.002 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                             (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (int k = 0; k < 3; ++k) p[k] = 0.5 * (lo[k] + hi[k]);
  }
  /// The next position.
  const double* next(const Fixture& f) {
    const double* turn = &f.points[3 * i];  // uniform in the box: a direction change
    for (int k = 0; k < 3; ++k) {
      d[k] = 0.9 * d[k] + 0.1 * ((turn[k] - lo[k]) / (hi[k] - lo[k]) - 0.5);
      p[k] += step * d[k];
      if (p[k] < lo[k] || p[k] > hi[k]) d[k] = -d[k], p[k] = std::clamp(p[k], lo[k], hi[k]);
    }
    i = (i + 1) & ((f.points.size() / 3) - 1);
    return p;
  }
};

void BM_WalkAndList(benchmark::State& state) {
  const Fixture& f = fixture();
  Walk walk(f.pvs->handle());
  size_t total = 0;
  for (auto _ : state) {
    const double* p = walk.next(f);
    const viewcells::runtime::ObjectList l = f.pvs->objects_at(p[0], p[1], p[2]);
    total += l.size + (l.empty() ? 0 : l.data[l.size - 1]);
  }
  benchmark::DoNotOptimize(total);
  counters(state);
}

/// A compact handle: every query decodes its cell's lists along the path to the root (the worst
/// case: random viewpoints, a new cell each time).
void BM_LocateAndCopyCompact(benchmark::State& state) {
  const Fixture& f = fixture();
  const size_t n = f.points.size() / 3;
  std::vector<uint32_t> ids(f.compact->object_count());
  size_t i = 0, total = 0;
  for (auto _ : state) {
    const double* p = &f.points[3 * i];
    const int32_t cell = f.compact->locate(p[0], p[1], p[2]);
    const size_t got = vc_pvs_cell_objects_copy(f.compact->handle(), cell, ids.data(), ids.size());
    total += got + (got ? ids[got - 1] : 0);
    i = (i + 1) & (n - 1);
  }
  benchmark::DoNotOptimize(total);
  counters(state);
}

/// A compact handle along the walk of BM_WalkAndList, decoding only when the camera enters
/// another cell (as an engine keeps the current cell's set).
void BM_WalkAndCopyCompact(benchmark::State& state) {
  const Fixture& f = fixture();
  Walk walk(f.compact->handle());
  std::vector<uint32_t> ids(f.compact->object_count());
  int32_t current = -2;
  size_t total = 0, count = 0;
  for (auto _ : state) {
    const double* p = walk.next(f);
    const int32_t cell = f.compact->locate(p[0], p[1], p[2]);
    if (cell != current) {
      count = vc_pvs_cell_objects_copy(f.compact->handle(), cell, ids.data(), ids.size());
      current = cell;
    }
    total += count + (count ? ids[count - 1] : 0);
  }
  benchmark::DoNotOptimize(total);
  counters(state);
}

void BM_LocateAndBitRow(benchmark::State& state) {
  const Fixture& f = fixture();
  const size_t n = f.points.size() / 3;
  std::vector<uint8_t> row(f.pvs->row_bytes());
  size_t i = 0;
  for (auto _ : state) {
    const double* p = &f.points[3 * i];
    vc_pvs_cell_bits(f.pvs->handle(), f.pvs->locate(p[0], p[1], p[2]), row.data(), row.size());
    benchmark::DoNotOptimize(row.data());
    i = (i + 1) & (n - 1);
  }
  counters(state);
}

/// Opening the file, as an engine does when a level loads: zstd, decoding the lists and
/// expanding every cell's visible set. VIEWCELLS_BENCH_PVS_FORMAT1 may name the same cells
/// written in format 1 (`viewcells recode --format 1`), timed the same way.
void open_file(benchmark::State& state, const char* variable, bool compact = false) {
  const char* path = std::getenv(variable);
  if (!path) {
    state.SkipWithError((std::string(variable) + " is not set").c_str());
    return;
  }
  size_t cells = 0;
  for (auto _ : state) {
    const viewcells::runtime::PvsFile f(path, compact);
    cells += f.cell_count();
  }
  benchmark::DoNotOptimize(cells);
  state.SetItemsProcessed(state.iterations());
}
void BM_Open(benchmark::State& state) { open_file(state, "VIEWCELLS_BENCH_PVS"); }
void BM_OpenFormat1(benchmark::State& state) { open_file(state, "VIEWCELLS_BENCH_PVS_FORMAT1"); }
void BM_OpenCompact(benchmark::State& state) { open_file(state, "VIEWCELLS_BENCH_PVS", true); }

}  // namespace

BENCHMARK(BM_Open)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenFormat1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenCompact)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Locate);
BENCHMARK(BM_LocateAndList);
BENCHMARK(BM_WalkAndList);
BENCHMARK(BM_LocateAndCopyCompact);
BENCHMARK(BM_WalkAndCopyCompact);
BENCHMARK(BM_LocateAndBitRow);
BENCHMARK_MAIN();
