// Adaptive global visibility sampling: where a sample's contribution goes, that PVSs only
// grow, resuming, and independence of the thread count.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>

#include "support/test_scenes.h"
#include "viewcells/agvs/agvs.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

/// A kd-tree of `n` cells over the office's bounds, each leaf its own view cell.
CellLocator office_cells(const Scene& scene, uint32_t n) {
  const SegmentSet segs = test::sample_scene(scene, 20000, 3);
  SubdivisionConfig sc;
  sc.strategy = SplitStrategy::kKdCycling;
  sc.max_cells = n;
  sc.show_progress = false;
  Subdivision s = subdivide(scene, segs, CostModel{}, sc);
  std::vector<int32_t> leaf_cell(s.nodes.size(), -1);
  const std::vector<int32_t> leaves = s.leaves();
  for (size_t i = 0; i < leaves.size(); ++i) leaf_cell[leaves[i]] = static_cast<int32_t>(i);
  return CellLocator(std::move(s), std::move(leaf_cell), static_cast<uint32_t>(leaves.size()));
}

AgvsConfig quiet(AgvsMethod method, uint64_t samples) {
  AgvsConfig c;
  c.method = method;
  c.max_samples = samples;
  c.batch_size = 5000;
  c.show_progress = false;
  return c;
}

TEST(Agvs, ContributionGoesToEveryPiercedCellAndNoOther) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const CellLocator cells = office_cells(scene, 32);
  const Box3 box = cells.view_box();
  std::vector<std::tuple<int32_t, double, double>> stack;
  std::vector<int32_t> leaves, pierced;
  const Vec3 e = box.extent();
  const Vec3 a = box.lo + e * 0.1, b = box.lo + Vec3{0.9 * e.x, 0.7 * e.y, 0.8 * e.z};
  cells.cells_of_segment(a, b, pierced, stack, leaves);
  // The same cells as walking the segment in small steps.
  std::set<int32_t> walked;
  for (int k = 0; k <= 20000; ++k) walked.insert(cells.cell_at(a + (b - a) * (k / 20000.0)));
  EXPECT_EQ(std::set<int32_t>(pierced.begin(), pierced.end()), walked);
  ASSERT_GE(pierced.size(), 3u);
  GlobalPvs pvs(cells.cell_count(), static_cast<uint32_t>(scene.object_count()));
  bool contributed[2] = {false, false};
  EXPECT_EQ(contribute(pvs, pierced, 3, 5, contributed), 2 * pierced.size());
  EXPECT_TRUE(contributed[0] && contributed[1]);
  for (uint32_t c = 0; c < cells.cell_count(); ++c) {
    const bool in = walked.count(static_cast<int32_t>(c)) > 0;
    EXPECT_EQ(pvs.list(c), in ? std::vector<uint32_t>({3, 5}) : std::vector<uint32_t>()) << "cell " << c;
  }
  EXPECT_EQ(contribute(pvs, pierced, 3, 5), 0u) << "nothing new the second time";
  EXPECT_EQ(contribute(pvs, pierced, 5, kNoObject), 0u);
  EXPECT_EQ(contribute(pvs, {pierced[0]}, 7, 7), 1u) << "one object seen at both ends counts once";
}

TEST(Agvs, PvsOnlyGrowsAndResumes) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 1});
  const CellLocator cells = office_cells(scene, 40);
  const auto caster = make_embree_caster(scene);
  AgvsSolver solver(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 20000));
  solver.run();
  const GlobalPvs first = solver.pvs();
  EXPECT_GT(first.entries(), 0u);
  solver.set_limits(50000, 0, 0);  // totals
  solver.run();
  const GlobalPvs& second = solver.pvs();
  // Limits are checked between batches; a silhouette search may add a second sample.
  EXPECT_GE(solver.stats().samples, 50000u);
  EXPECT_LT(solver.stats().samples, 50000u + 2 * 5000u);
  EXPECT_GE(second.entries(), first.entries());
  for (uint32_t c = 0; c < cells.cell_count(); ++c)
    for (uint32_t o : first.list(c)) EXPECT_TRUE(second.contains(c, o));
  double before = 0;
  for (const AgvsPoint& p : solver.stats().curve) {
    EXPECT_GE(p.mean_pvs, before);
    before = p.mean_pvs;
  }
  // Every distribution was drawn from, the mutation once candidates existed.
  for (int d = 0; d < AgvsStats::kDistributions; ++d)
    EXPECT_GT(solver.stats().dist_samples[d], 0u) << to_string(AgvsDistribution(d));
}

TEST(Agvs, IdenticalForOneAndTwoThreads) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 4});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  for (AgvsMethod m : {AgvsMethod::kAgvs, AgvsMethod::kSgvs, AgvsMethod::kRef}) {
    GlobalPvs one, two;
    {
      ThreadLimit limit(1);
      AgvsSolver s(scene, *caster, cells, quiet(m, 30000));
      s.run();
      one = s.pvs();
    }
    {
      ThreadLimit limit(2);
      AgvsSolver s(scene, *caster, cells, quiet(m, 30000));
      s.run();
      two = s.pvs();
    }
    EXPECT_TRUE(one == two) << to_string(m);
    EXPECT_GT(one.entries(), 0u);
  }
}

TEST(Agvs, GlobalSamplingSeesMoreThanPerCellSampling) {
  // The same number of samples: a global sample serves every cell its segment pierces.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 1});
  const CellLocator cells = office_cells(scene, 60);
  const auto caster = make_embree_caster(scene);
  double mean[3];
  for (AgvsMethod m : {AgvsMethod::kAgvs, AgvsMethod::kSgvs, AgvsMethod::kRef}) {
    AgvsSolver s(scene, *caster, cells, quiet(m, 100000));
    s.run();
    mean[static_cast<int>(m)] = s.mean_pvs();
  }
  EXPECT_GT(mean[1], mean[2]) << "SGVS over REF";
  EXPECT_GT(mean[0], mean[1]) << "AGVS over SGVS";
}

TEST(Agvs, MeasuredPixelError) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  const CellLocator cells = office_cells(scene, 16);
  const auto caster = make_embree_caster(scene);
  GlobalPvs empty(cells.cell_count(), static_cast<uint32_t>(scene.object_count())), full = empty;
  for (uint32_t c = 0; c < cells.cell_count(); ++c)
    for (uint32_t o = 0; o < scene.object_count(); ++o) full.insert(c, o);
  // Inside a closed office every pixel shows something: all wrong with no PVS, none with all.
  const PixelErrorMeasure none = measure_pixel_error(scene, *caster, cells, empty, 5, 64, 64, 90, 1, true);
  EXPECT_EQ(none.cameras, 5u);
  EXPECT_GT(none.share, 0.9);
  EXPECT_NEAR(none.pixels, none.share * 1024 * 1024, 1e-6);
  EXPECT_EQ(measure_pixel_error(scene, *caster, cells, full, 5, 64, 64, 90, 1, true).pixels, 0.0);
}

TEST(Agvs, SavedStateResumesExactly) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 5});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  const std::string path = test::temp_path("state.vagvs");
  AgvsSolver whole(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 40000));
  whole.run();
  uint64_t first_samples = 0;
  {
    AgvsSolver first(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 20000));
    first.run();
    first_samples = first.stats().samples;
    first.save(path, 42);
  }
  {
    AgvsSolver mem(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 20000));
    mem.run();
    mem.set_limits(40000, 0, 0);
    mem.run();
    EXPECT_TRUE(mem.pvs() == whole.pvs()) << "in-memory resume";
  }
  AgvsSolver second(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 40000));
  EXPECT_THROW(second.load(path, 43), Error) << "another scene or other cells";
  EXPECT_EQ(second.stats().samples, 0u) << "a refused load changes nothing";
  second.load(path, 42);
  EXPECT_EQ(second.stats().samples, first_samples);
  {
    second.save(path + "2", 42);
    std::ifstream a(path, std::ios::binary), b(path + "2", std::ios::binary);
    std::string x(std::istreambuf_iterator<char>(a), {}), y(std::istreambuf_iterator<char>(b), {});
    EXPECT_EQ(x, y) << "save, load, save: the same bytes";
  }
  second.run();
  EXPECT_TRUE(second.pvs() == whole.pvs()) << "resuming continues exactly where the run stopped";
  EXPECT_EQ(second.stats().rays, whole.stats().rays);
  AgvsSolver other(scene, *caster, cells, quiet(AgvsMethod::kSgvs, 10));
  EXPECT_THROW(other.load(path, 42), Error) << "another method";
  // A damaged file is refused.
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  test::write_file(path, bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(second.load(path, 42), Error);
}

TEST(Agvs, BadInput) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  const CellLocator cells = office_cells(scene, 8);
  const auto caster = make_embree_caster(scene);
  AgvsSolver s(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 0));
  EXPECT_THROW(s.run(), Error) << "no limit";
  EXPECT_THROW(parse_agvs_method("fast"), Error);
  AgvsConfig bad = quiet(AgvsMethod::kAgvs, 10);
  bad.window_p = 1.5;
  EXPECT_THROW(AgvsSolver(scene, *caster, cells, bad), Error);
}

}  // namespace
}  // namespace viewcells
