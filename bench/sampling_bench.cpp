// Micro-benchmarks of the sampling stage: raw Embree rays, paired rays, and whole samples.
// Run: scripts/build.sh build-release Release -DVIEWCELLS_BUILD_BENCH=ON && build-release/bench/viewcells_bench
#include <benchmark/benchmark.h>

#include "viewcells/core/parallel.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

const Scene& city() {
  static const Scene scene = generate_scene({GeneratorKind::kCity, 1, 8});
  return scene;
}

void BM_EmbreeRawRays(benchmark::State& state) {
  ThreadLimit one(1);
  const auto caster = make_embree_caster(city());
  SamplerConfig config;
  config.samples = 50000;
  const std::vector<Ray> rays = sampled_rays(city(), *caster, config);
  for (auto _ : state) benchmark::DoNotOptimize(caster->time_raw(rays));
  state.SetItemsProcessed(state.iterations() * rays.size());
}
BENCHMARK(BM_EmbreeRawRays)->Unit(benchmark::kMillisecond);

void BM_EmbreePairs(benchmark::State& state) {
  const auto caster = make_embree_caster(city());
  SamplerConfig config;
  config.samples = 50000;
  config.empty_space = EmptySpaceMode::kOff;  // only primary pairs
  const std::vector<Ray> rays = sampled_rays(city(), *caster, config);
  std::vector<Vec3> origins, dirs;
  for (size_t i = 0; i < rays.size(); i += 2) {
    origins.push_back(rays[i].origin);
    dirs.push_back(rays[i].dir);
  }
  std::vector<Hit> hits(rays.size());
  for (auto _ : state) caster->intersect_pairs(origins, dirs, hits);
  state.SetItemsProcessed(state.iterations() * rays.size());
}
BENCHMARK(BM_EmbreePairs)->Unit(benchmark::kMillisecond);

void BM_SampleSegments(benchmark::State& state) {
  ThreadLimit one(1);
  const auto caster = make_embree_caster(city());
  SamplerConfig config;
  config.samples = 50000;
  config.show_progress = false;
  for (auto _ : state) benchmark::DoNotOptimize(sample_segments(city(), *caster, config));
  state.SetItemsProcessed(state.iterations() * config.samples);
}
BENCHMARK(BM_SampleSegments)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace viewcells
