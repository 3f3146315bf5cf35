// The pipeline driven as a library, as a second driver (an engine plugin, a farm) would: build,
// bake under budgets, the PVSs of coarser cuts, reports.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <nlohmann/json.hpp>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/q3/bsp_file.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pipeline/measure.h"
#include "viewcells/pipeline/play.h"
#include "viewcells/pipeline/pvs.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/pipeline/sampling.h"
#include "viewcells/q3/level.h"
#include "viewcells/q3/play.h"
#include "viewcells/q3/view_space.h"
#include "viewcells/core/rng.h"
#include "viewcells/runtime.hpp"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

const pipeline::Log quiet = [](const std::string&) {};

const std::string& office() {
  static const std::string path = [] {
    const std::string p = test::temp_path("pipeline-office.obj");
    write_obj(generate_scene({GeneratorKind::kOffice, 1, 1}), p);
    return p;
  }();
  return path;
}

pipeline::BuildConfig small_build(const std::string& hierarchy) {
  pipeline::BuildConfig c;
  c.scene.path = office();
  c.sampling.samples = 20000;
  c.sampling.show_progress = false;
  c.subdivision.max_cells = 120;
  c.subdivision.show_progress = false;
  c.hierarchy_path = hierarchy;
  return c;
}

TEST(Pipeline, BuildWritesWhatItReturnsAndReportsIt) {
  const std::string path = test::temp_path("pipeline.vcells");
  const pipeline::BuildResult r = pipeline::build(small_build(path), quiet);
  const SubdivisionFile back = read_subdivision(path);
  EXPECT_EQ(back.subdivision.leaf_count(), r.file.subdivision.leaf_count());
  ASSERT_TRUE(back.history && r.file.history);
  EXPECT_EQ(back.history->leaf_count, r.file.history->leaf_count);
  EXPECT_EQ(back.leaf_pvs, r.file.leaf_pvs);
  const auto j = nlohmann::json::parse(pipeline::report_json(r));
  EXPECT_EQ(j["command"], "build");
  EXPECT_EQ(j["subdivision"]["cells"], r.file.subdivision.leaf_count());
  EXPECT_TRUE(j.contains("embree_isa"));
  EXPECT_EQ(j["counts"]["valid_segments"], r.sampling.result.stats.valid_segments);
}

/// A kind of level the pipeline has never seen: viewers in the lower half of the scene's box,
/// each cell weighing half its volume. Nothing in the pipeline changes for it.
class LowerHalf final : public ViewSpace {
 public:
  explicit LowerHalf(const Box3& bounds) : box_(bounds) { box_.hi.z = 0.5 * (bounds.lo.z + bounds.hi.z); }
  std::string describe() const override { return "the lower half"; }
  std::string box_rule() const override { return "the lower half's box"; }
  void restrict(SamplerConfig& config) const override {
    const double top = box_.hi.z;
    config.view_space = [top](const Vec3& p) { return p.z <= top; };
    if (config.view_box.empty()) config.view_box = box_;
  }
  std::function<void(Subdivision&)> weigher(const Box3&) const override {
    return [](Subdivision& s) {
      for (BspNode& n : s.nodes) n.weight = 0.5 * n.volume;
    };
  }
  std::string weight_rule() const override { return "half their volume"; }

 protected:
  CameraSet place_cameras(const Scene&, const RayCaster&, const CameraConfig&,
                          const std::function<int32_t(const Vec3&)>&, const CellLocator*) const override {
    return {};
  }

 private:
  Box3 box_;
};

TEST(Pipeline, AViewSpaceOfItsOwnChangesNothingInThePipeline) {
  pipeline::BuildConfig c = small_build("");
  c.merge = false;
  // The scene's own view space (the whole box): cells weigh their volume.
  const pipeline::BuildResult plain = pipeline::build(c, pipeline::load_scene_for_rays(c.scene, quiet), quiet);
  const Box3 bounds = plain.sampling.loaded.scene->bounds;
  for (const BspNode& n : plain.file.subdivision.nodes) EXPECT_DOUBLE_EQ(n.weight, n.volume);
  EXPECT_EQ(plain.sampling.result.segments.view_box, bounds);
  // The same build asking another view space: its box, its origins, its weights, its words.
  pipeline::LoadedScene loaded = pipeline::load_scene_for_rays(c.scene, quiet);
  const auto lower = std::make_shared<const LowerHalf>(loaded.scene->bounds);
  loaded.view_space = lower;
  const pipeline::BuildResult r = pipeline::build(c, std::move(loaded), quiet);
  Box3 expected = bounds;
  expected.hi.z = 0.5 * (bounds.lo.z + bounds.hi.z);
  EXPECT_EQ(r.sampling.result.segments.view_box, expected);
  for (const BspNode& n : r.file.subdivision.nodes) EXPECT_DOUBLE_EQ(n.weight, 0.5 * n.volume);
  const auto j = nlohmann::json::parse(pipeline::report_json(r));
  EXPECT_EQ(j["settings"]["view_space"], "the lower half");
  EXPECT_EQ(j["settings"]["view_box_source"], "the lower half's box");
  // It knows no players: play cameras and --play-space are refused, naming it.
  CameraConfig play;
  play.placement = CameraPlacement::kPlay;
  try {
    lower->check_cameras(play);
    ADD_FAILURE() << "play cameras accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the lower half"), std::string::npos) << e.what();
  }
  CameraConfig none;
  none.count = 0;
  EXPECT_THROW(lower->check_cameras(none), Error);
  EXPECT_EQ(lower->play_space(*r.sampling.loaded.scene, *r.sampling.loaded.caster), nullptr);
}

TEST(Pipeline, PlaySpaceNeedsFloorsAndIsTheOnlyDensity) {
  pipeline::BuildConfig c = small_build("");
  c.subdivision.play_space = true;
  // The office's floors: its play space weighs the cells.
  const pipeline::BuildResult r = pipeline::build(c, quiet);
  EXPECT_NE(r.play_space.find("walkable floors"), std::string::npos) << r.play_space;
  // Cubes with no floor a player could reach (1 m^2 tops, no start points): none.
  c.scene.path = test::temp_path("cubes.obj");
  write_obj(test::cube_grid(3), c.scene.path);
  try {
    pipeline::build(c, quiet);
    ADD_FAILURE() << "--play-space on cubes was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--play-space needs a view space that knows where players stand: the scene "
                                         "has none"),
              std::string::npos)
        << e.what();
  }
  c.scene.path = "level.bsp";  // checked before the file is read
  c.subdivision.density = {true, 0.0, 2.0, 0.1};
  EXPECT_THROW(pipeline::build(c, quiet), Error);
  c.subdivision.density = {};
  c.sampling.view_box = Box3{{0, 0, 0}, {1, 1, 1}};
  EXPECT_THROW(pipeline::build(c, quiet), Error);
}

TEST(Pipeline, PlaySpaceWeighsCellsWherePlayersAreAndAgvsDrawsThere) {
  const std::string path = test::oa_dm2_path(VIEWCELLS_DATA_DIR);
  if (path.empty()) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  pipeline::BuildConfig c;
  c.scene.path = path;
  c.sampling.samples = 30000;
  c.sampling.show_progress = false;
  c.subdivision.max_cells = 150;
  c.subdivision.show_progress = false;
  c.subdivision.play_space = true;
  pipeline::BuildResult r = pipeline::build(c, quiet);
  const auto j = nlohmann::json::parse(pipeline::report_json(r));
  EXPECT_TRUE(j["effects"]["viewpoint_density"]["enabled"]) << j["effects"].dump();
  // Each cell weighs its volume in the play space's leaves: in all, the play space's volume.
  pipeline::LoadedScene& loaded = r.sampling.loaded;
  const PlaySpace play = q3_play_space(*q3_map_of(loaded.level.get()), *loaded.scene, *loaded.caster, PlaySpaceConfig{});
  // The build kept the play space it found, for AGVS to share (a bake finds it once).
  const std::shared_ptr<const ViewSpace> found = pipeline::play_view_space(loaded);
  EXPECT_EQ(found->viewpoint_rule(), play.rule);
  const Subdivision& s = r.file.subdivision;
  double total = 0;
  for (int32_t l : s.leaves()) total += s.nodes[l].weight;
  EXPECT_NEAR(total, play.play_volume, 1e-6 * play.play_volume);
  EXPECT_LT(total, 0.99 * play.open_volume);
  // AGVS's points: in the play space's leaves, uniform over them by volume (the share in the
  // leaves west of the middle against their share of the volume, within 5 sigma).
  AgvsConfig a;
  pipeline::play_view_space(loaded)->restrict(a);
  ASSERT_TRUE(a.view_point_map && a.view_space);
  EXPECT_EQ(pipeline::play_view_space(loaded), found) << "the play space was found again";
  const Q3Map& map = *q3_map_of(loaded.level.get());
  const Subdivision q3 = q3_subdivision(map, q3_view_box(map));
  const size_t inner = map.nodes.size();
  double west_volume = 0;
  const double mid = q3_view_box(map).center().x;
  for (size_t l = 0; l < map.leaves.size(); ++l)
    if (play.leaves[l] && !q3.cells[inner + l].empty() && q3.cells[inner + l].bounds().center().x < mid)
      west_volume += q3.nodes[inner + l].volume;
  Rng rng(3);
  int drawn = 0, kept = 0, west = 0;
  for (; drawn < 40000; ++drawn) {
    const Vec3 p = a.view_point_map(rng.uniform(), rng.uniform(), rng.uniform());
    if (std::isnan(p.x)) continue;
    ++kept;
    const int32_t l = map.leaf_at(p);
    ASSERT_TRUE(play.leaves[l]) << "a point outside the play space";
    ASSERT_TRUE(a.view_space(p));
    ASSERT_TRUE(q3_in_view_space(map, p));
    west += q3.cells[inner + l].bounds().center().x < mid;
  }
  ASSERT_GT(kept, drawn / 10);
  const double share = west_volume / play.play_volume;
  EXPECT_NEAR(static_cast<double>(west) / kept, share, 5 * std::sqrt(share * (1 - share) / kept));
}

TEST(Pipeline, CoarserCutsSeeTheUnionOfTheirParts) {
  const pipeline::BuildResult r = pipeline::build(small_build(""), quiet);
  const SubdivisionFile& file = r.file;
  const MergeHistory& h = *file.history;
  const ViewCellSet fine = extract_by_count(h, 40);
  const PvsFile fine_file = pipeline::pvs_file_for(file, fine);
  std::vector<std::vector<uint32_t>> fine_lists(fine.cells.size());
  for (uint32_t i = 0; i < fine.cells.size(); ++i) fine_lists[i] = fine_file.pvs.cell_pvs(i);
  // The construction PVS of a merged cell is the union of its leaves': coarsening the fine
  // cells' PVSs must give exactly the coarse cells' own.
  for (size_t count : {40ul, 17ul, 3ul, 1ul}) {
    const ViewCellSet coarse = extract_by_count(h, count);
    const auto lists = pipeline::coarsen(h, fine.cells, fine_lists, coarse.cells);
    const PvsFile coarse_file = pipeline::pvs_file_for(file, coarse);
    ASSERT_EQ(lists.size(), count);
    for (uint32_t i = 0; i < count; ++i) EXPECT_EQ(lists[i], coarse_file.pvs.cell_pvs(i)) << count << " cells, cell " << i;
  }
}

pipeline::BakeConfig small_bake(const std::string& out) {
  pipeline::BakeConfig c;
  c.scene.path = office();
  c.sampling.samples = 3000;  // few: AGVS then finds much the construction samples missed
  c.sampling.show_progress = false;
  c.subdivision.max_cells = 200;
  c.subdivision.show_progress = false;
  c.agvs.max_samples = 150000;
  c.agvs.show_progress = false;
  // Greedy merging on the construction samples, and the whole view box (the office's floors would
  // make the play space the view space: AGVS's batches then split so that a run passes its sample
  // limit by one, which the measured stops' curves below count exactly): these tests are of the rest.
  c.merge_on_agvs = false;
  c.play_space_where_known = false;
  c.output = out;
  return c;
}

TEST(Pipeline, BakeHoldsTheMemoryBudgetForTheFileItWrites) {
  const std::string out = test::temp_path("budget.pvs");
  size_t coarsened = 0, fitted = 0;
  for (uint64_t budget = 2500; budget <= 9000; budget += 500) {
    pipeline::BakeConfig c = small_bake(out);
    c.memory = budget;
    c.near.rays_per_object = 0;  // the budget is what is tested, on AGVS's PVSs
    try {
      const pipeline::BakeResult r = pipeline::bake(c, quiet);
      ++fitted;
      EXPECT_LE(std::filesystem::file_size(out), budget);
      EXPECT_EQ(r.file_bytes, std::filesystem::file_size(out));
      coarsened += r.cells < r.agvs_cells;
      const runtime::PvsFile f(out);
      EXPECT_EQ(f.cell_count(), r.cells);
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("fit in"), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(fitted, 5u);
  RecordProperty("coarsened", static_cast<int>(coarsened));
}

TEST(Pipeline, BakeByCellsWritesThatManyAndContinuesFromItsWorkDirectory) {
  const std::string out = test::temp_path("cells.pvs"), work = test::temp_path("bake-work");
  pipeline::BakeConfig c = small_bake(out);
  c.cells = 9;
  c.work_dir = work;
  const pipeline::BakeResult first = pipeline::bake(c, quiet);
  EXPECT_EQ(first.cells, 9u);
  EXPECT_FALSE(first.hierarchy_reused);
  c.agvs.max_samples = 300000;
  const pipeline::BakeResult second = pipeline::bake(c, quiet);
  EXPECT_TRUE(second.hierarchy_reused);
  EXPECT_TRUE(second.agvs_resumed);
  EXPECT_GE(second.agvs.samples, 300000u);
  EXPECT_GE(second.pvs_entries, first.pvs_entries) << "sampling on only adds to the PVSs";
  // The same as one uninterrupted run of 300,000 samples.
  const std::string direct = test::temp_path("direct.pvs");
  pipeline::BakeConfig d = small_bake(direct);
  d.cells = 9;
  d.agvs.max_samples = 300000;
  pipeline::bake(d, quiet);
  const runtime::PvsFile a(out), b(direct);
  ASSERT_EQ(a.cell_count(), b.cell_count());
  for (int32_t i = 0; i < static_cast<int32_t>(a.cell_count()); ++i) {
    const auto x = a.objects(i), y = b.objects(i);
    EXPECT_EQ(std::vector<uint32_t>(x.begin(), x.end()), std::vector<uint32_t>(y.begin(), y.end())) << "cell " << i;
  }
  // Settings that change the hierarchy are not served from the work directory.
  c.sampling.seed = 2;
  EXPECT_FALSE(pipeline::bake(c, quiet).hierarchy_reused);
}

/// A small bake of the map at `path` into the temporary file `name` (20,000 AGVS samples).
pipeline::BakeConfig small_map_bake(const std::string& path, uint64_t samples, uint32_t max_cells, uint32_t cells,
                                    const std::string& name) {
  pipeline::BakeConfig c;
  c.scene.path = path;
  c.sampling.samples = samples;
  c.sampling.show_progress = false;
  c.subdivision.max_cells = max_cells;
  c.subdivision.show_progress = false;
  c.cells = cells;
  c.agvs.max_samples = 20000;
  c.agvs.show_progress = false;
  c.output = test::temp_path(name);
  return c;
}

TEST(Pipeline, BakedMapGivesEveryPointOfItsNonSolidSpaceACell) {
  // q3map2 rounds leaf bounds to whole units and derives them from portals: some non-solid
  // leaves reach past the union of the stored bounds (the bake's view box), and a player (or a
  // spectator, a noclip camera) there found no cell. The written file's cells reach out to
  // q3_cover_box, and the runtime, the toolkit and measure's play cameras all find one.
  const std::string path = test::oa_dm2_path(VIEWCELLS_DATA_DIR);
  if (path.empty()) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  pipeline::BakeConfig c = small_map_bake(path, 30000, 60, 20, "covered.pvs");
  c.subdivision.play_space = true;
  c.near.rays_per_object = 0;  // point location only: the PVSs' contents do not matter here
  pipeline::bake(c, quiet);
  const Q3Map map = read_q3bsp(path);
  const Box3 stored = q3_view_box(map), cover = q3_cover_box(map);
  const PvsFile f = read_pvs(c.output);
  const runtime::PvsFile r(c.output);
  EXPECT_TRUE(f.bsp.view_box.contains(cover.lo) && f.bsp.view_box.contains(cover.hi));
  // Points of non-solid leaves within their stored bounds enlarged by one unit: in each leaf's
  // bounds, and in the slabs of the cover box beyond the stored bounds' box.
  Rng rng(9);
  size_t tried = 0, beyond = 0;
  auto check = [&](const Vec3& p) {
    const int32_t l = map.leaf_at(p);
    const Q3Leaf& leaf = map.leaves[l];
    if (leaf.cluster < 0) return;
    for (int a = 0; a < 3; ++a)
      if (p[a] < leaf.bounds.lo[a] - 1 || p[a] > leaf.bounds.hi[a] + 1) return;
    ++tried;
    beyond += !stored.contains(p);
    const int32_t cell = r.locate(p.x, p.y, p.z);
    ASSERT_GE(cell, 0) << "leaf " << l << " at " << p.x << " " << p.y << " " << p.z;
    ASSERT_EQ(cell, f.locate(p));
  };
  for (const Q3Leaf& leaf : map.leaves) {
    if (leaf.cluster < 0 || leaf.bounds.empty()) continue;
    for (int k = 0; k < 40; ++k) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = rng.uniform(leaf.bounds.lo[a] - 1, leaf.bounds.hi[a] + 1);
      check(p);
    }
  }
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k < 20000; ++k) {
        Vec3 p{rng.uniform(cover.lo.x, cover.hi.x), rng.uniform(cover.lo.y, cover.hi.y),
               rng.uniform(cover.lo.z, cover.hi.z)};
        p[a] = side ? rng.uniform(stored.hi[a], cover.hi[a]) : rng.uniform(cover.lo[a], stored.lo[a]);
        check(p);
      }
  EXPECT_GT(tried, 1000u);
  EXPECT_GT(beyond, 0u) << "no point beyond the stored bounds: the test would pass without the cover box";
  // measure's play cameras: none in no cell.
  pipeline::MeasureConfig m;
  m.scene.path = path;
  m.pvs_path = c.output;
  m.cameras.count = 300;
  m.frame = {64, 48, 90.0, 1024 * 1024};
  const pipeline::MeasureResult mr = pipeline::measure(m, quiet);
  EXPECT_EQ(mr.error.cameras_uncovered, 0u);
  EXPECT_EQ(mr.error.cameras, 300u);
}

TEST(Pipeline, MeasureCountsACameraInNoCellAsAFrameDrawingNothing) {
  // A .pvs whose view box leaves out part of the map (what bakes wrote before the cover box):
  // measure once stopped at the first such player eye; now it measures it, every pixel wrong.
  const std::string path = test::oa_dm2_path(VIEWCELLS_DATA_DIR);
  if (path.empty()) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  pipeline::BakeConfig c = small_map_bake(path, 20000, 30, 10, "half.pvs");
  c.near.rays_per_object = 0;  // any PVSs will do: what is measured is a camera in no cell
  pipeline::bake(c, quiet);
  PvsFile f = read_pvs(c.output);
  Box3& box = f.bsp.view_box;  // 4% off each side along x and y: eyes there have no cell
  for (int a = 0; a < 2; ++a) {
    const double cut = 0.04 * (box.hi[a] - box.lo[a]);
    box.lo[a] += cut;
    box.hi[a] -= cut;
  }
  const std::string half = test::temp_path("half-box.pvs");
  write_pvs(half, f);
  pipeline::MeasureConfig m;
  m.scene.path = path;
  m.pvs_path = half;
  m.cameras.count = 200;
  m.frame = {64, 48, 90.0, 1024 * 1024};
  const pipeline::MeasureResult r = pipeline::measure(m, quiet);
  EXPECT_GT(r.error.cameras_uncovered, 0u);
  EXPECT_LT(r.error.cameras_uncovered, 100u);
  EXPECT_GE(r.error.cameras_wrong, r.error.cameras_uncovered) << "an eye in no cell sees the map";
  EXPECT_GT(r.error.worst_pixels, 1000.0);
  EXPECT_LE(r.error.p99_pixels, r.error.worst_pixels);
  // The worst frames, as cameras to look through again: the first is the worst pixel count,
  // each in the cell its eye is in, their objects' pixels adding up to the frame's.
  ASSERT_FALSE(r.worst_frames.empty());
  EXPECT_LE(r.worst_frames.size(), 10u);
  EXPECT_DOUBLE_EQ(r.worst_frames.front().pixels, r.error.worst_pixels);
  for (size_t i = 0; i < r.worst_frames.size(); ++i) {
    const pipeline::WrongFrame& w = r.worst_frames[i];
    if (i) {
      EXPECT_LE(w.pixels, r.worst_frames[i - 1].pixels);
    }
    uint64_t sum = 0;
    for (const auto& [o, px] : w.objects) sum += px;
    EXPECT_DOUBLE_EQ(static_cast<double>(sum) * 1024 * 1024 / (64 * 48), w.pixels);
    EXPECT_NEAR(length(w.forward), 1.0, 1e-9);
  }
}

TEST(Pipeline, BakeTimeBoundsTheWholeBake) {
  // A merge asked to reach a pixel error it never reaches ran on past --time: now each of its
  // AGVS runs stops at a quarter of it, and the PVSs' AGVS at what is left.
  pipeline::BakeConfig c = small_bake(test::temp_path("timed.pvs"));
  c.cells = 5;
  c.agvs.max_samples = 0;
  c.merge_agvs = AgvsConfig{};
  c.merge_agvs->pixel_error = 1e-300;
  c.merge_agvs->show_progress = false;
  c.max_seconds = 4.0;  // room for the hierarchy on a loaded or sanitized machine
  const pipeline::BakeResult r = pipeline::bake(c, quiet);
  EXPECT_LT(r.seconds, 12.0) << "a bound of 4 s (tests never assert tight times)";
  EXPECT_EQ(r.agvs.stop_reason, "reached the time limit");
  // A limit the hierarchy uses up is an error, not a file of unsampled PVSs.
  c.max_seconds = 1e-3;
  EXPECT_THROW(pipeline::bake(c, quiet), Error);
  EXPECT_FALSE(std::filesystem::exists(test::temp_path("timed-none.pvs")));
}

TEST(Pipeline, BakeMeetsAHoleTargetThatIndependentCamerasConfirm) {
  // The target: at most 5% of frames with any wrong pixel. First a bake stopped early (one AGVS
  // batch) misses it, so the check below can fail; then a bake that stops on it meets it, and
  // cameras of another seed (never the bake's) confirm it within their sampling error.
  auto holes_of = [](const std::string& pvs, uint64_t seed) {
    pipeline::MeasureConfig m;
    m.scene.path = office();
    m.pvs_path = pvs;
    m.cameras.count = 400;
    m.cameras.seed = seed;
    m.frame = {128, 96, 90.0, 1024 * 1024};
    const pipeline::MeasureResult r = pipeline::measure(m, quiet);
    return static_cast<double>(r.error.cameras_wrong) / r.error.cameras;
  };
  const double target = 0.05, slack = 3 * std::sqrt(target * (1 - target) / 400);
  const std::string early = test::temp_path("holes-early.pvs"), met = test::temp_path("holes-met.pvs");
  pipeline::BakeConfig c = small_bake(early);
  c.cells = 60;
  c.agvs.max_samples = 1000;
  c.agvs.batch_size = 1000;
  c.near.rays_per_object = 0;  // AGVS alone
  pipeline::bake(c, quiet);
  const double early_holes = holes_of(early, 2);
  EXPECT_GT(early_holes, target + slack) << "a bake of one batch should miss the target";
  // The same batch with near-object samples (bake's default) only adds entries: never more
  // holes, and here far fewer.
  const std::string near = test::temp_path("holes-near.pvs");
  c.output = near;
  c.near = NearSampleConfig{};
  const pipeline::BakeResult with_near = pipeline::bake(c, quiet);
  EXPECT_GT(with_near.near.added, 0u);
  EXPECT_LT(holes_of(near, 2), early_holes);
  c = small_bake(met);
  c.cells = 60;
  c.agvs.max_samples = 0;
  c.agvs.batch_size = 1000;
  c.holes = target;
  c.measure_cameras = 200;
  c.frame = {128, 96, 90.0, 1024 * 1024};
  const pipeline::BakeResult r = pipeline::bake(c, quiet);
  ASSERT_TRUE(r.measured_stop) << r.agvs.stop_reason;
  ASSERT_FALSE(r.measured_curve.empty());
  const PixelErrorMeasure& last = r.measured_curve.back().measured;
  EXPECT_LE(static_cast<double>(last.cameras_wrong) / last.cameras, target);
  EXPECT_EQ(r.measured_curve.back().eta_seconds, 0.0);
  EXPECT_LE(holes_of(met, 2), target + slack) << "independent cameras find more holes than the bake measured";
}

TEST(Pipeline, BakeRefusesNoBudgetOrTwo) {
  pipeline::BakeConfig c = small_bake(test::temp_path("none.pvs"));
  EXPECT_THROW(pipeline::bake(c, quiet), Error);
  c.cells = 4;
  c.memory = 100000;
  EXPECT_THROW(pipeline::bake(c, quiet), Error);
}

/// The measured stopping rule's curve: first after one batch, then at every doubling of the
/// samples, each measurement above the target but the last, which is within it.
void expect_stopped_at_measured_error(const std::vector<pipeline::MeasuredPoint>& curve, uint64_t batch,
                                      double target) {
  ASSERT_GE(curve.size(), 2u) << "one batch of " << batch << " samples does not see all the cameras show";
  EXPECT_EQ(curve.front().samples, batch);
  for (size_t k = 0; k + 1 < curve.size(); ++k) {
    EXPECT_GT(curve[k].measured.pixels, target) << "measurement " << k;
    EXPECT_GE(curve[k + 1].samples, 2 * curve[k].samples) << "measurement " << k;
  }
  EXPECT_LE(curve.back().measured.pixels, target);
}

/// bake --measured-error: AGVS stops at the first measurement whose cameras' mean error is
/// within the target (after one batch, then at every doubling), and the error the report gives
/// is what `viewcells measure` finds in the file written with the same cameras, also when a
/// memory budget coarsened the cells after sampling.
TEST(Pipeline, BakeStopsAtAMeasuredErrorAndReportsWhatMeasureFinds) {
  auto measured_by_measure = [](const std::string& pvs, const pipeline::BakeConfig& c) {
    pipeline::MeasureConfig m;
    m.scene.path = office();
    m.pvs_path = pvs;
    m.cameras = c.cameras;
    m.cameras.count = c.measure_cameras;
    m.frame = c.frame;
    return pipeline::measure(m, quiet).error.pixels;
  };
  const std::string out = test::temp_path("bake-measured.pvs");
  pipeline::BakeConfig c = small_bake(out);
  c.cells = 60;
  c.agvs.max_samples = 0;
  c.agvs.batch_size = 250;
  c.measure_cameras = 64;
  c.frame.width = c.frame.height = 128;  // one wrong pixel is 64 of 1024 x 1024, 1 in the mean of 64 cameras
  c.measured_error = 0.5;                // so: no wrong pixel at all
  const pipeline::BakeResult r = pipeline::bake(c, quiet);
  // (With 16 cameras, one batch of 1,000 samples saw all they show on one kernel.)
  expect_stopped_at_measured_error(r.measured_curve, 250, c.measured_error);
  EXPECT_TRUE(r.measured_stop);
  EXPECT_NE(r.agvs.stop_reason.find("measured pixel error"), std::string::npos) << r.agvs.stop_reason;
  EXPECT_EQ(r.agvs.samples, r.measured_curve.back().samples) << "no sample after the last measurement";
  ASSERT_TRUE(r.measured);
  EXPECT_LE(r.measured->pixels, c.measured_error);
  EXPECT_EQ(r.measured->pixels, measured_by_measure(out, c));
  const auto j = nlohmann::json::parse(pipeline::report_json(r));
  EXPECT_EQ(j["measured_pixel_error"]["pixels"], r.measured->pixels);
  EXPECT_EQ(j["measured_curve"].size(), r.measured_curve.size());

  // A memory budget below the sampled cells' file: coarser cells, each camera's found again in
  // them, and the file written measured as `measure` measures it.
  const std::string small = test::temp_path("bake-measured-small.pvs");
  pipeline::BakeConfig m = c;
  m.cells = 0;
  m.output = small;
  m.measured_error = 0;
  m.agvs.max_samples = 20000;  // far more than the construction's 3,000: the sampled cells outgrow the budget
  bool coarsened = false;
  for (uint64_t budget = 2500; budget <= 9000 && !coarsened; budget += 500) {
    m.memory = budget;
    pipeline::BakeResult coarse;
    try {
      coarse = pipeline::bake(m, quiet);
    } catch (const Error&) {
      continue;  // not even the coarsest cut fits
    }
    ASSERT_TRUE(coarse.measured);
    EXPECT_TRUE(coarse.measured_curve.empty());
    EXPECT_EQ(coarse.measured->cameras, 64u);
    EXPECT_EQ(coarse.measured->pixels, measured_by_measure(small, m)) << budget << " bytes";
    coarsened = coarse.cells < coarse.agvs_cells;
  }
  EXPECT_TRUE(coarsened) << "no budget from 2,500 to 9,000 bytes coarsened the cells sampled";

  // A measured error without cameras: the library decides 5,000 (64x48, as `measure`'s), and
  // says so.
  c.measure_cameras = 0;
  c.frame.width = c.frame.height = 0;
  std::vector<std::string> decided;
  const pipeline::BakeConfig resolved = pipeline::resolve(c, &decided);
  EXPECT_EQ(resolved.measure_cameras, 5000u);
  EXPECT_EQ(resolved.frame.width, 64u);
  ASSERT_EQ(decided.size(), 2u);
  EXPECT_EQ(decided[0], "5000 measuring cameras (for the measured pixel error)");
}

/// pvs --measured-error: sampling stops at the first measurement (after one batch, then at
/// every doubling) whose cameras' mean error is within the target; every earlier one was not;
/// another limit reached first stops it too, and says so.
TEST(Pipeline, PvsStopsAtAMeasuredError) {
  const std::string hierarchy = test::temp_path("measured.vcells");
  pipeline::build(small_build(hierarchy), quiet);
  pipeline::PvsConfig c;
  c.hierarchy_path = hierarchy;
  c.scene_path = office();
  c.cells = 60;
  c.agvs.batch_size = 1000;
  c.agvs.show_progress = false;
  c.measure_cameras = 16;
  c.measure_size = 128;  // one wrong pixel is 64 of 1024 x 1024, 4 in the mean of 16 cameras
  c.measured_error = 1;  // so: no wrong pixel at all
  c.output = test::temp_path("measured.pvs");
  const pipeline::PvsResult r = pipeline::compute_pvs(c, quiet);
  expect_stopped_at_measured_error(r.measured_curve, 1000, c.measured_error);
  EXPECT_EQ(r.stats.samples, r.measured_curve.back().samples) << "no sample after the last measurement";
  EXPECT_NE(r.stats.stop_reason.find("measured pixel error"), std::string::npos) << r.stats.stop_reason;
  ASSERT_TRUE(r.measured);
  EXPECT_EQ(r.measured->pixels, r.measured_curve.back().measured.pixels) << "the file written is the one measured";
  // A sample limit below what the error needs stops it first.
  c.agvs.max_samples = 1500;
  const pipeline::PvsResult limited = pipeline::compute_pvs(c, quiet);
  EXPECT_EQ(limited.stats.stop_reason.find("measured"), std::string::npos) << limited.stats.stop_reason;
  EXPECT_GE(limited.stats.samples, 1500u);
  EXPECT_EQ(limited.stats.samples, limited.measured_curve.back().samples);
  ASSERT_TRUE(limited.measured);
  EXPECT_EQ(limited.measured->pixels, limited.measured_curve.back().measured.pixels);
  // The rule needs cameras, and chooses its own measurements.
  c.measure_cameras = 0;
  EXPECT_THROW(pipeline::compute_pvs(c, quiet), Error);
  c.measure_cameras = 16;
  c.measure_at = {5000};
  EXPECT_THROW(pipeline::compute_pvs(c, quiet), Error);
}

}  // namespace
}  // namespace viewcells

namespace viewcells {
namespace {

/// A level format the library does not know, brought by its front end (this test) as a Quake 3
/// map's reader is brought by the command line: lines "box NAME X0 Y0 Z0 X1 Y1 Z1" and
/// "start X Y Z", in metres.
RawMesh read_boxes_level(const std::string& path) {
  std::istringstream in(read_file_bytes(path));
  RawMesh mesh;
  std::string word;
  int line = 0;
  for (std::string text; std::getline(in, text);) {
    ++line;
    std::istringstream l(text);
    if (!(l >> word)) continue;
    if (word == "box") {
      std::string name;
      Vec3 lo, hi;
      if (!(l >> name >> lo.x >> lo.y >> lo.z >> hi.x >> hi.y >> hi.z)) throw Error(path, line, "box NAME X0 Y0 Z0 X1 Y1 Z1");
      test::add_cube(mesh, lo, hi, name);
    } else if (word == "start") {
      Vec3 p;
      if (!(l >> p.x >> p.y >> p.z)) throw Error(path, line, "start X Y Z");
      mesh.start_points.push_back(p);
    } else {
      throw Error(path, line, "unknown line '" + word + "'");
    }
  }
  mesh.metres_per_unit = 1;
  return mesh;
}

// A second level format without touching the pipeline: registered by its front end, a file of
// it loads, and bake finds its play space from its start point as it would a glTF's spawn node.
TEST(Pipeline, ALevelFormatRegisteredByItsFrontEndBakesThroughThePipeline) {
  const std::string level = test::temp_path("room.vcboxes");
  test::write_file(level,
                   "box floor 0 0 -0.2 12 12 0\nbox pillar 5 5 0 6 6 3\nbox crate 2 8 0 2.8 8.8 0.8\n"
                   "box wall 8 0 0 8.3 12 3\nstart 2 2 0.5\n");
  EXPECT_THROW(load_scene(level), Error) << "an unregistered extension is an error";
  register_scene_format({".vcboxes", "boxes level", read_boxes_level});
  const Scene scene = load_scene(level);
  EXPECT_EQ(scene.object_count(), 4u);
  ASSERT_EQ(scene.start_points.size(), 1u);
  pipeline::BakeConfig c;
  c.scene.path = level;
  c.cells = 4;
  c.sampling.samples = 5000;
  c.agvs.max_samples = 5000;
  c.near.rays_per_object = 0;
  c.sampling.show_progress = c.subdivision.show_progress = c.agvs.show_progress = false;
  const pipeline::BakeResult r = pipeline::bake(c, [](const std::string&) {});
  EXPECT_EQ(r.cells, 4u);
  EXPECT_NE(r.view_space_choice.find("reachable from 1 of 1 start points"), std::string::npos) << r.view_space_choice;
  // The wall at x = 8 to 8.3 cuts the room: walking from the start reaches the side x < 8 only,
  // and the side beyond joins as a region within the 10 m margin; with only_from_starts it does not.
  pipeline::SceneSource source = c.scene;
  const pipeline::FoundPlaySpace joined = pipeline::find_play_space(source, [](const std::string&) {});
  source.floors.only_from_starts = true;
  const pipeline::FoundPlaySpace strict = pipeline::find_play_space(source, [](const std::string&) {});
  ASSERT_TRUE(joined.space && strict.space);
  EXPECT_NEAR(strict.space->floor_area(), 8 * 12 - 1 - 0.64, 3.0) << strict.why;
  EXPECT_NEAR(joined.space->floor_area(), 8 * 12 - 1 - 0.64 + 3.7 * 12, 4.0) << joined.why;
}

}  // namespace
}  // namespace viewcells
