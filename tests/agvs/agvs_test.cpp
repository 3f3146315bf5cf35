// Adaptive global visibility sampling: where a sample's contribution goes, that PVSs only
// grow, resuming, independence of the thread count, the penumbra of dynamic edits, edits
// followed by resumed sampling, and the visibility filter.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include "../../libviewcells/src/agvs/candidates.h"
#include "support/test_scenes.h"
#include "viewcells/agvs/agvs.h"
#include "viewcells/eval/frames.h"
#include "viewcells/agvs/penumbra.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/core/rng.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

/// A kd-tree of `n` cells over the office's bounds, each leaf its own view cell.
CellLocator office_cells(const Scene& scene, uint32_t n) { return test::kd_cells(scene, n); }

AgvsConfig quiet(AgvsMethod method, uint64_t samples) {
  AgvsConfig c;
  c.method = method;
  c.max_samples = samples;
  c.batch_size = 5000;
  c.show_progress = false;
  return c;
}

TEST(Agvs, MutationCandidatesComeLeastMutatedFirstAndTheMostMutatedAreDropped) {
  // The buffer against its definition (a set ordered by (times taken, id)), over random adds
  // and takes with a small cap, and through a save and load half-way.
  using agvs_detail::Candidate;
  using agvs_detail::CandidateBuffer;
  constexpr size_t kCap = 40;
  CandidateBuffer buffer;
  std::set<std::pair<uint32_t, uint64_t>> model;
  std::map<uint64_t, uint32_t> times_of;
  uint64_t next = 0;
  Rng rng(3, 7);
  const Box3 box{{-1, -1, -1}, {1, 1, 1}};
  for (int step = 0; step < 20000; ++step) {
    if (step == 10000) {
      ByteWriter w;
      buffer.save(w);
      const std::string bytes = w.take();
      ByteReader r(bytes, "state");
      buffer = CandidateBuffer::load(r, kCap, bytes.size(), box, 1u << 30);
      ASSERT_TRUE(r.at_end());
    }
    if (model.empty() || rng.uniform() < 0.35) {
      Candidate c;
      c.object = static_cast<uint32_t>(next);  // tags the candidate with its id
      buffer.add(c, kCap);
      model.insert({0u, next});
      times_of[next++] = 0;
      if (model.size() > kCap) {
        times_of.erase(std::prev(model.end())->second);
        model.erase(std::prev(model.end()));
      }
    } else {
      const auto [times, id] = *model.begin();
      model.erase(model.begin());
      model.insert({times + 1, id});
      times_of[id] = times + 1;
      ASSERT_EQ(buffer.take().object, id) << "step " << step;
    }
    ASSERT_EQ(buffer.size(), model.size());
  }
  // Out of order in the file: refused.
  ByteWriter w;
  w.put<uint64_t>(5);
  w.put<uint64_t>(2);
  for (uint64_t id : {3, 1}) {
    w.put(id), w.put<uint32_t>(0);
    w.put(Vec3{}), w.put(Vec3{}), w.put(0.0), w.put(0.0), w.put(kNoObject);
  }
  const std::string bad = w.take();
  ByteReader r(bad, "state");
  EXPECT_THROW(CandidateBuffer::load(r, kCap, bad.size(), box, 1), Error);
}

TEST(Agvs, CellsOfASegmentAreThoseOfTheLeavesItPierces) {
  // The walk stops at subtrees that lie in one cell; it must report exactly the cells of the
  // leaves a full walk reaches, also for segments in split planes and ending on them, and
  // through geometry-aligned planes (the rotated office).
  const Scene scene = generate_scene({GeneratorKind::kRotatedOffice, 1, 3});
  SubdivisionConfig sc;
  sc.max_cells = 96;
  sc.show_progress = false;
  sc.geometry_aligned = GeometryAlignedMode::kOn;
  const Subdivision s = subdivide(scene, test::sample_scene(scene, 20000, 5), CostModel{}, sc);
  const std::vector<int32_t> leaves = s.leaves();
  ASSERT_GT(leaves.size(), 60u);
  // Cells of whole subtrees (the leaves under each node of an earlier cut), and cells that are
  // not (leaves dealt round), so that the walk both stops early and goes to the leaves.
  std::vector<int32_t> by_subtree(s.nodes.size(), -1), dealt(s.nodes.size(), -1);
  const std::vector<int32_t> earlier = s.leaves_after(12);
  for (size_t c = 0; c < earlier.size(); ++c) {
    std::vector<int32_t> todo{earlier[c]};
    while (!todo.empty()) {
      const int32_t n = todo.back();
      todo.pop_back();
      if (s.nodes[n].plane < 0) by_subtree[n] = static_cast<int32_t>(c);
      else todo.insert(todo.end(), {s.nodes[n].child[0], s.nodes[n].child[1]});
    }
  }
  for (size_t i = 0; i < leaves.size(); ++i) dealt[leaves[i]] = static_cast<int32_t>(i % 7);
  const Box3 box = s.view_box;
  const Vec3 e = box.extent();
  std::vector<std::pair<Vec3, Vec3>> segments;
  Rng rng(9, 1);
  auto point = [&] { return box.lo + Vec3{e.x * rng.uniform(), e.y * rng.uniform(), e.z * rng.uniform()}; };
  for (int k = 0; k < 3000; ++k) segments.push_back({point(), point()});
  // In and onto axis-aligned split planes.
  for (const SplitRecord& r : s.splits) {
    const Plane& plane = s.planes[s.nodes[r.node].plane];
    if (plane.axis < 0) continue;
    Vec3 a = point(), b = point();
    a[plane.axis] = b[plane.axis] = plane.offset;
    segments.push_back({a, b});
    Vec3 c = point();
    c[plane.axis] = plane.offset;
    segments.push_back({point(), c});
  }
  // And one cell for everything: the walk stops at the root.
  std::vector<int32_t> one(s.nodes.size(), -1);
  for (int32_t l : leaves) one[l] = 0;
  size_t several_leaves_a_cell = 0;
  for (const std::vector<int32_t>* cells_of : {&by_subtree, &dealt, &one}) {
    const std::vector<int32_t>& leaf_cell = *cells_of;
    const uint32_t count = 1 + static_cast<uint32_t>(*std::max_element(leaf_cell.begin(), leaf_cell.end()));
    const CellLocator cells(s, leaf_cell, count);
    std::vector<std::tuple<int32_t, double, double>> stack;
    std::vector<int32_t> got, reached;
    for (const auto& [a, b] : segments) {
      cells.cells_of_segment(a, b, got, stack);
      reached.clear();
      s.leaves_of_segment(a, b, reached, stack);
      std::vector<int32_t> want;
      for (int32_t l : reached) want.push_back(leaf_cell[l]);
      std::sort(want.begin(), want.end());
      want.erase(std::unique(want.begin(), want.end()), want.end());
      ASSERT_EQ(got, want);
      if (cells_of == &by_subtree) several_leaves_a_cell += want.size() < reached.size();
    }
  }
  EXPECT_GT(several_leaves_a_cell, 100u);  // walks that can stop above the leaves
}

TEST(Agvs, ContributionGoesToEveryPiercedCellAndNoOther) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const CellLocator cells = office_cells(scene, 32);
  const Box3 box = cells.view_box();
  std::vector<std::tuple<int32_t, double, double>> stack;
  std::vector<int32_t> pierced;
  const Vec3 e = box.extent();
  const Vec3 a = box.lo + e * 0.1, b = box.lo + Vec3{0.9 * e.x, 0.7 * e.y, 0.8 * e.z};
  cells.cells_of_segment(a, b, pierced, stack);
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

/// A state with any one of its values replaced by 1e300, NaN or a huge count (a corrupt or
/// hostile file whose checksum is right) is refused with an Error, or loads and then samples
/// on without crashing: rays from such values once reached Embree and aborted.
TEST(Agvs, HostileValuesInAValidStateAreRefusedOrHarmless) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  const CellLocator cells = office_cells(scene, 4);
  const auto caster = make_embree_caster(scene);
  AgvsConfig config = quiet(AgvsMethod::kAgvs, 600);
  config.batch_size = 200;
  config.mutation_buffer = 8;
  AgvsSolver first(scene, *caster, cells, config);
  first.run();
  const std::string path = test::temp_path("hostile.vagvs");
  first.save(path, 7);
  uint32_t version = 0;
  const std::string payload = read_container(path, "VAGS", 99, version);
  ASSERT_GT(payload.size(), 64u);
  const double huge = 1e300, nan = std::nan("");
  const uint64_t count = uint64_t{1} << 62;
  size_t loaded = 0, refused = 0;
  for (size_t at = 8; at + 8 <= payload.size(); at += 4) {
    for (const void* value : {static_cast<const void*>(&huge), static_cast<const void*>(&nan),
                              static_cast<const void*>(&count)}) {
      std::string bad = payload;
      std::memcpy(bad.data() + at, value, 8);
      const std::string bad_path = test::temp_path("hostile_bad.vagvs");
      write_container(bad_path, "VAGS", version, bad);
      AgvsSolver solver(scene, *caster, cells, config);
      try {
        solver.load(bad_path, 7);
        ++loaded;
        solver.set_limits(solver.stats().samples + 400, 0, 0);
        solver.run();
      } catch (const Error&) {
        ++refused;
      }
    }
  }
  EXPECT_GT(refused, 0u);
  std::printf("payload %zu bytes: %zu altered states loaded, %zu refused\n", payload.size(), loaded, refused);
  EXPECT_GT(loaded, 0u) << "values that do not matter to sampling (timings, statistics) still load";
}

TEST(Agvs, IdenticalForOneAndTwoThreads) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 4});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  // AGVS also with mutation lanes, which draw and take their candidates in parallel.
  for (const auto& [m, lanes] : {std::pair{AgvsMethod::kAgvs, 1u}, std::pair{AgvsMethod::kAgvs, 7u},
                                 std::pair{AgvsMethod::kSgvs, 1u}, std::pair{AgvsMethod::kRef, 1u}}) {
    AgvsConfig config = quiet(m, 30000);
    config.mutation_lanes = lanes;
    GlobalPvs one, two;
    uint64_t rays[2] = {};
    {
      ThreadLimit limit(1);
      AgvsSolver s(scene, *caster, cells, config);
      s.run();
      one = s.pvs();
      rays[0] = s.stats().rays;
    }
    {
      ThreadLimit limit(2);
      AgvsSolver s(scene, *caster, cells, config);
      s.run();
      two = s.pvs();
      rays[1] = s.stats().rays;
    }
    EXPECT_TRUE(one == two) << to_string(m) << ", " << lanes << " lanes";
    EXPECT_EQ(rays[0], rays[1]) << to_string(m) << ", " << lanes << " lanes";
    EXPECT_GT(one.entries(), 0u);
  }
}

TEST(Agvs, AViewSpaceKeepsBatchesFullAndResultsIndependentOfThreads) {
  // A view space of a fifth of the box: the stationary distributions' chunks are Halton index
  // ranges sized from the share of points inside so far, their points outside skipped, so a
  // batch holds about the samples asked for, and nothing depends on the threads.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 4});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  const Box3 box = cells.view_box();
  const double cut = box.lo.x + 0.2 * box.extent().x;
  for (AgvsMethod m : {AgvsMethod::kAgvs, AgvsMethod::kSgvs}) {
    AgvsConfig config = quiet(m, 40000);
    config.view_space = [cut](const Vec3& p) { return p.x < cut; };
    AgvsStats stats[2];
    GlobalPvs pvs[2];
    for (int t = 0; t < 2; ++t) {
      ThreadLimit limit(t + 1);
      AgvsSolver s(scene, *caster, cells, config);
      s.run();
      stats[t] = s.stats();
      pvs[t] = s.pvs();
    }
    EXPECT_TRUE(pvs[0] == pvs[1]) << to_string(m);
    EXPECT_EQ(stats[0].rays, stats[1].rays) << to_string(m);
    EXPECT_EQ(stats[0].samples, stats[1].samples) << to_string(m);
    EXPECT_GT(pvs[0].entries(), 0u);
    // Batches of 5,000: the yield estimate keeps each within a few percent of that (the first
    // from a test of the first 4,096 indices), where drawing as many indices as samples would
    // give a fifth.
    const double per_batch = static_cast<double>(stats[0].samples) / static_cast<double>(stats[0].batches);
    EXPECT_NEAR(per_batch, 5000, 250) << to_string(m);
    EXPECT_GT(stats[0].dist_samples[0], 0u);
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

TEST(Agvs, RefCastsOneRayPerSample) {
  // The paper's REF: a random cell, a random point in it, one ray; the object it hits first
  // joins that cell's PVS, so a sample adds at most one entry.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 4});
  const CellLocator cells = office_cells(scene, 12);
  const auto caster = make_embree_caster(scene);
  AgvsSolver ref(scene, *caster, cells, quiet(AgvsMethod::kRef, 40000));
  ref.run();
  EXPECT_EQ(ref.stats().rays, ref.stats().samples);
  EXPECT_GT(ref.pvs().entries(), 0u);
  EXPECT_LE(ref.pvs().entries(), ref.stats().samples);
  // Global sampling with fewer rays (two per sample, and re-casts) finds more.
  AgvsSolver sgvs(scene, *caster, cells, quiet(AgvsMethod::kSgvs, 15000));
  sgvs.run();
  EXPECT_LE(sgvs.stats().rays, ref.stats().rays);  // re-casts from inside solids included
  EXPECT_GT(sgvs.pvs().entries(), ref.pvs().entries());
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

TEST(Agvs, EstimateOrBoundAgainstTheMeasuredError) {
  // SGVS stopped at doubling sample counts; at each stop cameras rendered against the same
  // PVSs. After the first batch, either a window is full and its estimate is within a factor
  // of 2 of the measurement, or the 90% upper bound is given, and it lies above it.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 1});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  AgvsSolver solver(scene, *caster, cells, quiet(AgvsMethod::kSgvs, 0));
  int bounds = 0;
  for (uint64_t n : {10000, 20000, 40000, 80000, 160000}) {
    solver.set_limits(n, 0, 0);
    solver.run();
    const double estimate = solver.pixel_error(), bound = solver.pixel_error_bound();
    ASSERT_NE(std::isnan(estimate), std::isnan(bound)) << "an estimate or a bound, never both";
    const double measured = measure_pixel_error(scene, *caster, cells, solver.pvs(), 4000, 16, 16, 90, 9, true).pixels;
    ASSERT_GT(measured, 0.0);
    if (!std::isnan(estimate)) {
      EXPECT_GT(estimate, 0.5 * measured) << n << " samples";
      EXPECT_LT(estimate, 2.0 * measured) << n << " samples";
    } else {
      EXPECT_GE(bound, measured) << n << " samples";
      ++bounds;
    }
  }
  EXPECT_GT(bounds, 0);
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

/// Mutation lanes: every lane is fed and drawn from (the mutations keep their share of the
/// samples), a state resumes exactly with its lanes, and a state of other lanes is refused.
TEST(Agvs, MutationLanesAreFedDrawnAndResumed) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 5});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  const std::string path = test::temp_path("lanes.vagvs");
  auto config = [](uint32_t lanes, uint64_t samples) {
    AgvsConfig c = quiet(AgvsMethod::kAgvs, samples);
    c.mutation_lanes = lanes;
    c.mutation_buffer = 700;  // 100 a lane: some lanes fill and drop their most mutated
    return c;
  };
  AgvsSolver whole(scene, *caster, cells, config(7, 40000));
  whole.run();
  const AgvsStats& st = whole.stats();
  EXPECT_LE(st.mutation_candidates, 700u) << "each lane keeps at most its 100";
  EXPECT_GT(st.mutation_candidates, 600u) << "lanes are fed evenly: most are full";
  AgvsSolver single(scene, *caster, cells, config(1, 40000));
  single.run();
  for (const int d : {static_cast<int>(AgvsDistribution::kTwoPointMutation),
                      static_cast<int>(AgvsDistribution::kSilhouetteMutation)}) {
    // The mutations get samples with lanes as without (the mixture's weights decide; a lane
    // without candidates would hand its share to the view space-direction samples).
    EXPECT_GT(st.dist_samples[d], 0u) << to_string(AgvsDistribution(d));
    EXPECT_GT(double(st.dist_samples[d]), 0.5 * double(single.stats().dist_samples[d]))
        << to_string(AgvsDistribution(d));
  }
  {
    AgvsSolver first(scene, *caster, cells, config(7, 20000));
    first.run();
    first.save(path, 42);
  }
  AgvsSolver other(scene, *caster, cells, config(3, 40000));
  EXPECT_THROW(other.load(path, 42), Error) << "another number of lanes";
  AgvsSolver second(scene, *caster, cells, config(7, 40000));
  second.load(path, 42);
  second.run();
  EXPECT_TRUE(second.pvs() == whole.pvs()) << "resuming continues exactly where the run stopped";
  EXPECT_EQ(second.stats().rays, whole.stats().rays);
  EXPECT_EQ(second.stats().mutation_candidates, st.mutation_candidates);
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
  for (uint32_t lanes : {0u, 100u}) {
    AgvsConfig c = quiet(AgvsMethod::kAgvs, 10);
    c.mutation_buffer = 50;
    c.mutation_lanes = lanes;
    EXPECT_THROW(AgvsSolver(scene, *caster, cells, c), Error) << lanes << " lanes";
  }
}

/// A copy of the scene with a closed, outward box appended as a new object.
Scene with_box(const Scene& scene, const Box3& b, const std::string& name) {
  Scene out = scene;
  const uint32_t base = static_cast<uint32_t>(out.vertices.size());
  for (int k = 0; k < 8; ++k)
    out.vertices.push_back({k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z});
  // Quads (counter-clockwise from outside) of the faces -x, +x, -y, +y, -z, +z.
  const uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  const uint32_t id = static_cast<uint32_t>(out.objects.size());
  for (const auto& q : quads) {
    out.triangles.push_back({base + q[0], base + q[1], base + q[2]});
    out.triangles.push_back({base + q[0], base + q[2], base + q[3]});
    out.triangle_object.push_back(id);
    out.triangle_object.push_back(id);
  }
  ObjectInfo info;
  info.name = name;
  out.objects.push_back(info);
  out.finalize();
  return out;
}

TEST(Penumbra, MatchesTheShadowOfAPlate) {
  // A plate at x = 5 (|y|, |z| <= 1) seen from the cell [-1, 1]^3. At depth x = 10 its
  // penumbra reaches |y| <= 1 + 2 t with t = 5 / (5 - 1): 3.5.
  const std::vector<Vec3> plate = {{5, -1, -1}, {5, 1, -1}, {5, 1, 1}, {5, -1, 1}};
  const Box3 cell({-1, -1, -1}, {1, 1, 1});
  const ConvexRegion p = penumbra(plate, cell, 100);
  ASSERT_FALSE(p.is_everything());
  auto at = [](double x, double y0, double y1) { return Box3({x - 0.01, y0, -0.05}, {x + 0.01, y1, 0.05}); };
  EXPECT_TRUE(p.may_intersect(at(10, -0.1, 0.1))) << "right behind the plate";
  EXPECT_TRUE(p.may_intersect(at(10, 3.4, 3.45))) << "inside the penumbra's edge";
  EXPECT_FALSE(p.may_intersect(at(10, 3.55, 3.8))) << "just outside it";
  EXPECT_FALSE(p.may_intersect(at(3, -0.1, 0.1))) << "between the cell and the plate";
  EXPECT_FALSE(p.may_intersect(at(10, 40, 50)));
  EXPECT_TRUE(p.may_intersect(at(5, -0.1, 0.1))) << "the plate itself";
  // An occluder touching the cell may hide anything from some point of it.
  const std::vector<Vec3> touching = {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}};
  EXPECT_TRUE(penumbra(touching, cell, 100).is_everything());
  // The same at 1e5 and rotated coordinates: a region made of hull planes, no tolerance loss.
  std::vector<Vec3> far_plate;
  for (const Vec3& v : plate) far_plate.push_back(v + Vec3{1e5, 1e5, 1e5});
  const Box3 far_cell(cell.lo + Vec3{1e5, 1e5, 1e5}, cell.hi + Vec3{1e5, 1e5, 1e5});
  const ConvexRegion q = penumbra(far_plate, far_cell, 100);
  const Vec3 o{1e5, 1e5, 1e5};
  EXPECT_TRUE(q.may_intersect(Box3(at(10, 3.4, 3.45).lo + o, at(10, 3.4, 3.45).hi + o)));
  EXPECT_FALSE(q.may_intersect(Box3(at(10, 3.55, 3.8).lo + o, at(10, 3.55, 3.8).hi + o)));
}

TEST(Agvs, DeletingAndInsertingAnObjectRestoresAConsistentSolution) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 3, 2});
  const CellLocator cells = office_cells(scene, 40);
  const auto caster = make_embree_caster(scene);
  // A wall across the whole building at mid x: afterwards nothing on one side of it is
  // visible from the other.
  const Box3 vb = cells.view_box();
  const double mid = 0.5 * (vb.lo.x + vb.hi.x);
  const Box3 wall({mid - 0.05, scene.bounds.lo.y - 1, scene.bounds.lo.z - 1},
                  {mid + 0.05, scene.bounds.hi.y + 1, scene.bounds.hi.z + 1});
  const Scene walled = with_box(scene, wall, "inserted_wall");
  const auto walled_caster = make_embree_caster(walled);
  const uint32_t n = static_cast<uint32_t>(scene.object_count()), wall_id = n;
  // Entries (cell left of the wall, object right of it), or the other way round.
  auto across = [&](const GlobalPvs& pvs) {
    uint64_t count = 0;
    for (uint32_t c = 0; c < cells.cell_count(); ++c) {
      const Box3& cb = cells.cell_bounds(c);
      for (uint32_t o : pvs.list(c)) {
        if (o >= n) continue;
        const Box3& ob = scene.objects[o].bounds;
        count += (cb.hi.x < wall.lo.x && ob.lo.x > wall.hi.x) || (cb.lo.x > wall.hi.x && ob.hi.x < wall.lo.x);
      }
    }
    return count;
  };
  AgvsSolver solver(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 60000));
  solver.run();
  const GlobalPvs before = solver.pvs();
  const uint64_t across_before = across(before);
  ASSERT_GT(across_before, 20u) << "the corridor must see across the middle";

  // Insert the wall: every entry it may hide goes, the rest stays.
  std::vector<uint32_t> same(n);
  for (uint32_t o = 0; o < n; ++o) same[o] = o;
  const AgvsEditStats ins = solver.edit(walled, *walled_caster, same);
  EXPECT_EQ(ins.inserted, 1u);
  EXPECT_EQ(ins.deleted, 0u);
  EXPECT_GT(ins.removed_penumbra, across_before);
  EXPECT_EQ(solver.pvs().object_count(), n + 1);
  EXPECT_EQ(across(solver.pvs()), 0u) << "the penumbra covers what lies behind the wall";
  EXPECT_GT(solver.pvs().entries(), before.entries() / 4) << "entries in front of the wall stay";
  for (uint32_t c = 0; c < cells.cell_count(); ++c)
    for (uint32_t o : solver.pvs().list(c)) EXPECT_TRUE(before.contains(c, o)) << "an edit adds nothing";
  EXPECT_TRUE(std::isnan(solver.pixel_error())) << "the estimator restarts";

  // Resumed sampling finds the wall and what is still visible, and nothing behind the wall.
  solver.set_limits(120000, 0, 0);
  solver.run();
  EXPECT_EQ(across(solver.pvs()), 0u);
  uint32_t cells_seeing_wall = 0;
  for (uint32_t c = 0; c < cells.cell_count(); ++c) cells_seeing_wall += solver.pvs().contains(c, wall_id);
  EXPECT_GT(cells_seeing_wall, cells.cell_count() / 4);
  // Consistent with a solution computed on the walled scene from scratch with as many samples.
  AgvsSolver fresh(walled, *walled_caster, cells, quiet(AgvsMethod::kAgvs, 120000));
  fresh.run();
  EXPECT_EQ(across(fresh.pvs()), 0u);
  EXPECT_NEAR(solver.mean_pvs(), fresh.mean_pvs(), 0.15 * fresh.mean_pvs());

  // Delete the wall: it leaves every PVS, and resumed sampling sees across again.
  std::vector<uint32_t> without(n + 1);
  for (uint32_t o = 0; o <= n; ++o) without[o] = o < n ? o : kNoObject;
  const AgvsEditStats del = solver.edit(scene, *caster, without);
  EXPECT_EQ(del.deleted, 1u);
  EXPECT_EQ(del.removed_deleted, cells_seeing_wall);
  EXPECT_EQ(solver.pvs().object_count(), n);
  solver.set_limits(240000, 0, 0);
  solver.run();
  EXPECT_GT(across(solver.pvs()), across_before / 2) << "the view across the middle is found again";

  // A map that is not one-to-one is refused and changes nothing.
  std::vector<uint32_t> twice(n, 0);
  const uint64_t entries = solver.pvs().entries();
  EXPECT_THROW(solver.edit(scene, *caster, twice), Error);
  EXPECT_EQ(solver.pvs().entries(), entries);
  // So is an edited scene that cannot be sampled (nothing rendered), after all the work.
  Scene dark = walled;
  for (ObjectInfo& o : dark.objects) o.rendered = false;
  const auto dark_caster = make_embree_caster(dark);
  std::vector<uint32_t> plus_wall(n);
  for (uint32_t o = 0; o < n; ++o) plus_wall[o] = o;
  EXPECT_THROW(solver.edit(dark, *dark_caster, plus_wall), Error);
  EXPECT_EQ(solver.pvs().entries(), entries);
  EXPECT_EQ(solver.pvs().object_count(), n);
  solver.set_limits(250000, 0, 0);
  solver.run();  // still sampling the scene it had
}

TEST(Agvs, CellNeighboursWithoutSplitRecords) {
  // A BSP read from a .pvs file has nodes but no split records: neighbours must not need them.
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  const SegmentSet segs = test::sample_scene(scene, 20000, 3);
  SubdivisionConfig sc;
  sc.strategy = SplitStrategy::kKdCycling;
  sc.max_cells = 24;
  sc.show_progress = false;
  Subdivision s = subdivide(scene, segs, CostModel{}, sc);
  std::vector<int32_t> leaf_cell(s.nodes.size(), -1);
  const std::vector<int32_t> leaves = s.leaves();
  for (size_t i = 0; i < leaves.size(); ++i) leaf_cell[leaves[i]] = static_cast<int32_t>(i);
  const auto n = static_cast<uint32_t>(leaves.size());
  const CellLocator with(s, leaf_cell, n);
  Subdivision bare = s;
  bare.splits.clear();
  bare.cells.clear();
  const CellLocator without(bare, leaf_cell, n);
  const auto a = with.neighbours(), b = without.neighbours();
  EXPECT_EQ(a, b);
  size_t pairs = 0;
  for (uint32_t c = 0; c < n; ++c) {
    EXPECT_FALSE(a[c].empty()) << "cell " << c << " has no neighbour";
    for (uint32_t d : a[c]) EXPECT_TRUE(std::binary_search(a[d].begin(), a[d].end(), c)) << "symmetric";
    pairs += a[c].size();
  }
  EXPECT_GE(pairs / 2, n - 1) << "the cells are connected";
}

TEST(Agvs, MatchObjectsByNameAndGeometry) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  const Scene walled = with_box(scene, Box3({0, 0, 0}, {1, 1, 1}), "inserted");
  const std::vector<uint32_t> m = match_objects(scene, walled);
  ASSERT_EQ(m.size(), scene.object_count());
  for (uint32_t o = 0; o < m.size(); ++o) EXPECT_EQ(m[o], o);
  const std::vector<uint32_t> back = match_objects(walled, scene);
  EXPECT_EQ(back.back(), kNoObject) << "the box was deleted";
  // A moved object is a deletion and an insertion.
  Scene moved = scene;
  for (uint32_t t = 0; t < moved.triangles.size(); ++t)
    if (moved.triangle_object[t] == 3)
      for (uint32_t v : moved.triangles[t]) moved.vertices[v].z += 0.0;
  moved.vertices[moved.triangles[std::find(moved.triangle_object.begin(), moved.triangle_object.end(), 3u) -
                                 moved.triangle_object.begin()][0]]
      .z += 0.25;
  moved.finalize();
  EXPECT_EQ(match_objects(scene, moved)[3], kNoObject);
}

TEST(Agvs, VisibilityFilterExtendsUndersampledPvss) {
  const Scene scene = generate_scene({GeneratorKind::kOffice, 2, 3});
  const CellLocator cells = office_cells(scene, 30);
  const auto caster = make_embree_caster(scene);
  AgvsConfig config = quiet(AgvsMethod::kAgvs, 600);
  config.batch_size = 200;
  config.filter_statistics = true;
  AgvsSolver solver(scene, *caster, cells, config);
  solver.run();
  EXPECT_THROW(AgvsSolver(scene, *caster, cells, quiet(AgvsMethod::kAgvs, 10)).filtered_pvs({}), Error)
      << "the object space filter needs the statistics";
  auto as_pvs = [&](const std::vector<std::vector<uint32_t>>& lists) {
    return GlobalPvs::from_lists(static_cast<uint32_t>(scene.object_count()), lists);
  };
  const GlobalPvs raw = solver.pvs();
  VisibilityFilter f;
  f.k = 0;
  const GlobalPvs k0 = as_pvs(solver.filtered_pvs(f));
  f.k = 1;
  const GlobalPvs k1 = as_pvs(solver.filtered_pvs(f));
  f.k = 4;
  const GlobalPvs k4 = as_pvs(solver.filtered_pvs(f));
  f.view_neighbours = 2;
  const GlobalPvs k4v = as_pvs(solver.filtered_pvs(f));
  // Supersets, growing with k and with the view space filter.
  for (uint32_t c = 0; c < cells.cell_count(); ++c)
    for (uint32_t o = 0; o < scene.object_count(); ++o) {
      if (raw.contains(c, o)) {
        EXPECT_TRUE(k0.contains(c, o));
      }
      if (k0.contains(c, o)) {
        EXPECT_TRUE(k1.contains(c, o));
      }
      if (k1.contains(c, o)) {
        EXPECT_TRUE(k4.contains(c, o));
      }
      if (k4.contains(c, o)) {
        EXPECT_TRUE(k4v.contains(c, o));
      }
    }
  EXPECT_GT(k4.entries(), k1.entries());
  EXPECT_GT(k4v.entries(), k4.entries());
  // Undersampled: the filter removes wrong pixels (the paper's figure 1).
  const auto error = [&](const GlobalPvs& p) {
    return measure_pixel_error(scene, *caster, cells, p, 40, 64, 64, 90, 5, true).pixels;
  };
  const double e_raw = error(raw), e_k1 = error(k1);
  EXPECT_GT(e_raw, 0.0);
  EXPECT_LT(e_k1, 0.5 * e_raw);
  // Dense sampling shrinks the extension: more samples, a smaller relative growth.
  AgvsConfig dense = config;
  dense.max_samples = 200000;
  AgvsSolver more(scene, *caster, cells, dense);
  more.run();
  f = VisibilityFilter{};
  const double growth_sparse = static_cast<double>(k1.entries()) / raw.entries();
  const double growth_dense = static_cast<double>(as_pvs(more.filtered_pvs(f)).entries()) / more.pvs().entries();
  EXPECT_LT(growth_dense, growth_sparse);
  // The filter is the same for any thread count.
  {
    ThreadLimit one(1);
    EXPECT_TRUE(as_pvs(solver.filtered_pvs(f)) == k1);
  }
}

}  // namespace
}  // namespace viewcells
