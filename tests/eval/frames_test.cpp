// Frames rendered at cameras (eval/frames.h): the measured pixel error against a count made
// by hand, and cameras placed where players stand on OpenArena's oa_dm2 (q3/play.h) with the
// map's own PVS measured by them.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "support/test_scenes.h"
#include "viewcells/core/parallel.h"
#include "viewcells/eval/frames.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/q3/play.h"
#include "viewcells/q3/view_space.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

TEST(Frames, WrongPixelsAreThoseOfObjectsMissingFromThePvs) {
  const Scene scene = test::cube_grid(4);
  const auto caster = make_embree_caster(scene);
  const CellLocator cells = test::kd_cells(scene, 8);
  std::vector<int32_t> cam_cells;
  const std::vector<Camera> cams = view_box_cameras(*caster, cells, 60, 5, true, cam_cells);
  ASSERT_EQ(cams.size(), 60u);
  // Incoherent single rays here, the kernel of the count by hand below (packets may differ in
  // the last bits: checked against this in the next test).
  const FrameConfig frame{24, 16, 90.0, 1024 * 1024, false};
  // Every object in every PVS: nothing is wrong.
  std::vector<std::vector<uint32_t>> all(cells.cell_count());
  for (auto& l : all)
    for (uint32_t o = 0; o < scene.object_count(); ++o) l.push_back(o);
  const PixelErrorMeasure full = measure_frames(scene, *caster, cams, cam_cells, GlobalPvs::from_lists(scene.object_count(), all), frame);
  EXPECT_EQ(full.share, 0.0);
  EXPECT_TRUE(full.wrong.empty());
  // Object 0 left out everywhere: the wrong pixels are exactly the pixels showing object 0,
  // counted here by casting every camera's rays one by one.
  for (auto& l : all) l.erase(l.begin());
  const PixelErrorMeasure m = measure_frames(scene, *caster, cams, cam_cells, GlobalPvs::from_lists(scene.object_count(), all), frame);
  const double f = std::tan(0.25 * std::numbers::pi);
  uint64_t expected = 0;
  std::vector<uint64_t> per_camera(cams.size(), 0);
  for (size_t k = 0; k < cams.size(); ++k)
    for (uint32_t y = 0; y < frame.height; ++y)
      for (uint32_t x = 0; x < frame.width; ++x) {
        const double sx = (2 * (x + 0.5) / frame.width - 1) * f, sy = (2 * (y + 0.5) / frame.height - 1) * f * 16 / 24;
        const Hit h = caster->intersect(Ray{cams[k].eye, normalize(cams[k].forward + cams[k].right * sx + cams[k].up * sy)});
        if (h.hit() && h.object == 0) ++per_camera[k];
      }
  for (uint64_t w : per_camera) expected += w;
  ASSERT_GT(expected, 0u) << "no camera sees object 0: choose another seed";
  uint64_t listed = 0;
  for (const WrongView& w : m.wrong) {
    EXPECT_EQ(w.object, 0u);
    EXPECT_EQ(w.pixels, per_camera[w.camera]);
    listed += w.pixels;
  }
  EXPECT_EQ(listed, expected);
  EXPECT_DOUBLE_EQ(m.share, static_cast<double>(expected) / (60.0 * 24 * 16));
  EXPECT_DOUBLE_EQ(m.pixels, m.share * 1024 * 1024);
  EXPECT_EQ(m.cameras_wrong, m.wrong.size());
  // The same with one thread.
  ThreadLimit one(1);
  const PixelErrorMeasure serial = measure_frames(scene, *caster, cams, cam_cells, GlobalPvs::from_lists(scene.object_count(), all), frame);
  EXPECT_EQ(serial.share, m.share);
  EXPECT_EQ(serial.median_pixels, m.median_pixels);
  EXPECT_EQ(m.cameras, 60u);
  EXPECT_EQ(m.cameras_asked, 60u);
  // A deadline already passed: no frame is rendered, and the measure says so (a bake's --time
  // cut its measurements this way, issue 67).
  FrameConfig late = frame;
  late.deadline = Deadline{std::chrono::steady_clock::now()};
  const PixelErrorMeasure cut = measure_frames(scene, *caster, cams, cam_cells, GlobalPvs::from_lists(scene.object_count(), all), late);
  EXPECT_EQ(cut.cameras, 0u);
  EXPECT_EQ(cut.cameras_asked, 60u);
  EXPECT_TRUE(cut.wrong.empty());
}

TEST(Frames, CoherentPacketsSeeWhatSingleRaysSeeAndEveryPixelOnce) {
  const Scene scene = generate_scene({GeneratorKind::kRotatedOffice, 1, 3});
  const auto caster = make_embree_caster(scene);
  const CellLocator cells = test::kd_cells(scene, 8);
  std::vector<int32_t> cam_cells;
  const std::vector<Camera> cams = view_box_cameras(*caster, cells, 40, 9, false, cam_cells);
  // 4x4 tiles clipped at the edges (37 x 23 is no multiple of 4): every pixel's ray once.
  const FrameConfig odd{37, 23, 75.0, 1024 * 1024};
  std::vector<Ray> tiled;
  frame_rays(cams[0], odd, tiled);
  ASSERT_EQ(tiled.size(), 37u * 23u);
  const double f = std::tan(0.5 * 75.0 * std::numbers::pi / 180.0);
  std::vector<int> met(tiled.size(), 0);
  for (const Ray& r : tiled) {
    // The pixel a ray goes through, from its direction in the camera's frame.
    const double along = dot(r.dir, cams[0].forward);
    const double sx = dot(r.dir, cams[0].right) / along, sy = dot(r.dir, cams[0].up) / along;
    const long x = std::lround(((sx / f) + 1) * 37 / 2 - 0.5), y = std::lround(((sy / (f * 23 / 37)) + 1) * 23 / 2 - 0.5);
    ASSERT_TRUE(x >= 0 && x < 37 && y >= 0 && y < 23);
    ++met[static_cast<size_t>(y) * 37 + static_cast<size_t>(x)];
  }
  for (int m : met) ASSERT_EQ(m, 1);
  // Packets and single rays: the same objects wrong, pixel counts within the kernels' last bits.
  std::vector<std::vector<uint32_t>> half(cells.cell_count());
  for (auto& l : half)
    for (uint32_t o = 0; o < scene.object_count(); o += 2) l.push_back(o);
  const GlobalPvs pvs = GlobalPvs::from_lists(scene.object_count(), half);
  FrameConfig frame{64, 48, 90.0, 1024 * 1024, true};
  const PixelErrorMeasure packets = measure_frames(scene, *caster, cams, cam_cells, pvs, frame);
  frame.coherent = false;
  const PixelErrorMeasure singles = measure_frames(scene, *caster, cams, cam_cells, pvs, frame);
  ASSERT_GT(singles.share, 0.0);
  EXPECT_NEAR(packets.share, singles.share, 1e-3 * singles.share);
  EXPECT_NEAR(packets.cameras_wrong, singles.cameras_wrong, 1.0);  // a one-pixel difference may flip one frame
  EXPECT_LE(packets.median_pixels, packets.p99_pixels);
  EXPECT_LE(packets.p99_pixels, packets.worst_pixels);
  // A camera in no cell: every pixel showing an object is wrong.
  std::vector<int32_t> none(cams.size(), -1);
  const PixelErrorMeasure lost = measure_frames(scene, *caster, cams, none, pvs, frame);
  EXPECT_EQ(lost.cameras_uncovered, cams.size());
  std::vector<std::vector<uint32_t>> nothing(cells.cell_count());
  const PixelErrorMeasure empty =
      measure_frames(scene, *caster, cams, cam_cells, GlobalPvs::from_lists(scene.object_count(), nothing), frame);
  EXPECT_EQ(lost.share, empty.share);
  EXPECT_EQ(empty.cameras_uncovered, 0u);
  // The rates of both ways, timed on the same frames.
  const FrameRayRates rates = frame_ray_rates(*caster, cams, frame, 100000);
  EXPECT_GE(rates.rays, 100000u);
  EXPECT_GT(rates.coherent_per_second, 0);
  EXPECT_GT(rates.incoherent_per_second, 0);
}

TEST(Frames, FrameSamplesAddWhatTheirFramesShowToTheirCells) {
  // From empty PVSs, the frames of some cameras fill their cells' lists: measured by the same
  // cameras and frames nothing is wrong, and other cameras still find holes (a sampler's own
  // cameras cannot measure it).
  const Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  const auto caster = make_embree_caster(scene);
  const CellLocator cells = test::kd_cells(scene, 16);
  std::vector<int32_t> cam_cells, other_cells;
  const std::vector<Camera> cams = view_box_cameras(*caster, cells, 40, 21, true, cam_cells);
  const std::vector<Camera> others = view_box_cameras(*caster, cells, 200, 22, true, other_cells);
  std::vector<std::vector<uint32_t>> lists(cells.cell_count());
  const FrameConfig frame{48, 36, 90.0, 1024 * 1024};
  std::vector<int32_t> with_none = cam_cells;
  with_none.push_back(-1);  // a camera in no cell adds nothing
  std::vector<Camera> with_extra = cams;
  with_extra.push_back(cams[0]);
  const uint64_t added = add_frame_samples(*caster, with_extra, with_none, frame, lists);
  uint64_t entries = 0;
  for (const auto& l : lists) {
    entries += l.size();
    EXPECT_TRUE(std::is_sorted(l.begin(), l.end()));
    EXPECT_TRUE(std::adjacent_find(l.begin(), l.end()) == l.end());
  }
  EXPECT_EQ(added, entries);
  ASSERT_GT(added, 0u);
  const GlobalPvs pvs = GlobalPvs::from_lists(scene.object_count(), lists);
  EXPECT_EQ(measure_frames(scene, *caster, cams, cam_cells, pvs, frame).cameras_wrong, 0u);
  EXPECT_GT(measure_frames(scene, *caster, others, other_cells, pvs, frame).cameras_wrong, 0u);
  // Adding the same frames again adds nothing; the result does not depend on the threads.
  EXPECT_EQ(add_frame_samples(*caster, cams, cam_cells, frame, lists), 0u);
  std::vector<std::vector<uint32_t>> serial(cells.cell_count());
  ThreadLimit one(1);
  add_frame_samples(*caster, cams, cam_cells, frame, serial);
  EXPECT_EQ(serial, lists);
}

TEST(Frames, PlayerCameraIsLevel) {
  const Camera c = camera_looking({1, 2, 3}, 0.7, 0.2);
  EXPECT_NEAR(length(c.forward), 1, 1e-12);
  EXPECT_NEAR(length(c.right), 1, 1e-12);
  EXPECT_NEAR(length(c.up), 1, 1e-12);
  EXPECT_NEAR(c.right.z, 0, 1e-12);  // no roll
  EXPECT_GT(c.up.z, 0);
  EXPECT_NEAR(dot(c.forward, c.right), 0, 1e-12);
  EXPECT_NEAR(dot(c.forward, c.up), 0, 1e-12);
  EXPECT_NEAR(std::asin(c.forward.z), 0.2, 1e-12);
}

/// oa_dm2, its scene and a caster, loaded once; null when the map is not fetched.
struct Dm2 {
  Q3Map map;
  Scene scene;
  std::unique_ptr<RayCaster> caster;
};
const Dm2* dm2() {
  static const std::unique_ptr<Dm2> loaded = []() -> std::unique_ptr<Dm2> {
    const std::string path = test::oa_dm2_path(VIEWCELLS_DATA_DIR);
    if (path.empty()) return nullptr;
    auto d = std::make_unique<Dm2>(Dm2{read_q3bsp(path), load_scene(path), nullptr});
    d->caster = make_embree_caster(d->scene);
    return d;
  }();
  return loaded.get();
}

TEST(Q3PlayCameras, PlayersStandOnReachableFloorsAndQ3map2sPvsShowsWhatTheySee) {
  const Dm2* d = dm2();
  if (!d) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  const Q3Map& map = d->map;
  const Scene& scene = d->scene;
  const RayCaster* caster = d->caster.get();
  PlayCameraConfig config;
  config.count = 400;
  const PlayCameras play = q3_play_cameras(map, scene, *caster, config);
  ASSERT_EQ(play.cameras.size(), 400u);
  EXPECT_GT(play.spawn_points, 0u);
  EXPECT_GT(play.reachable_leaves, play.open_leaves / 2);
  EXPECT_LE(play.reachable_leaves, play.open_leaves);
  const std::vector<bool> reachable = q3_reachable_leaves(map);
  for (size_t k = 0; k < play.cameras.size(); ++k) {
    const Camera& c = play.cameras[k];
    ASSERT_TRUE(q3_in_view_space(map, c.eye));
    ASSERT_TRUE(reachable[map.leaf_at(c.eye)]);
    ASSERT_EQ(play.leaves[k], map.leaf_at(c.eye));
    EXPECT_LE(std::abs(c.forward.z), std::sin(30 * std::numbers::pi / 180) + 1e-12);
    // A walkable floor eye_height below the eye, nothing between.
    const Hit down = caster->intersect(Ray{c.eye, {0, 0, -1}});
    ASSERT_TRUE(down.hit());
    EXPECT_NEAR(down.t, config.eye_height, 1e-3);
    EXPECT_TRUE(down.front);
    EXPECT_GE(normalize(scene.triangle_normal(down.triangle)).z, config.walk_normal);
  }
  // Drawn serially: the same cameras again.
  const PlayCameras again = q3_play_cameras(map, scene, *caster, config);
  ASSERT_EQ(again.points_drawn, play.points_drawn);
  EXPECT_EQ(again.cameras.back().eye, play.cameras.back().eye);
  // q3map2's PVS is conservative: players see nothing it rejects (the map's scene model is the
  // game's), except surfaces in no leaf, which the game never draws.
  const std::vector<std::vector<uint32_t>> admitted = q3_admitted_objects(scene, map);
  std::vector<int32_t> clusters;
  for (const Camera& c : play.cameras) clusters.push_back(map.leaves[map.leaf_at(c.eye)].cluster);
  const PixelErrorMeasure m = measure_frames(scene, *caster, play.cameras, clusters,
                                             GlobalPvs::from_lists(scene.object_count(), admitted), FrameConfig{64, 48});
  EXPECT_LE(m.share, 1e-5) << m.wrong.size() << " (camera, object) pairs wrong";
}


TEST(Q3PlaySpace, HoldsEveryPlayCameraAndIsTheSameForAnyThreadCount) {
  const Dm2* d = dm2();
  if (!d) GTEST_SKIP() << "oa_dm2.bsp not fetched (scripts/fetch-maps.sh)";
  const Q3Map& map = d->map;
  const Scene& scene = d->scene;
  const RayCaster* caster = d->caster.get();
  PlaySpaceConfig config;
  for (const auto& bad : {PlaySpaceConfig{0}, PlaySpaceConfig{1000, 1, 112, 0}, PlaySpaceConfig{1000, 1, 112, 1e-5},
                          PlaySpaceConfig{1000, 1, INFINITY}, PlaySpaceConfig{1000, 1, 112, 8, 1.5}})
    EXPECT_THROW(q3_play_space(map, scene, *caster, bad), Error);
  config.columns = 200000;
  const PlaySpace play = q3_play_space(map, scene, *caster, config);
  const std::vector<bool> reachable = q3_reachable_leaves(map);
  ASSERT_EQ(play.leaves.size(), map.leaves.size());
  size_t count = 0;
  for (size_t l = 0; l < map.leaves.size(); ++l) {
    count += play.leaves[l];
    if (play.leaves[l]) {
      ASSERT_TRUE(reachable[l]) << "leaf " << l;
    }
  }
  EXPECT_EQ(count, play.play_leaves);
  EXPECT_GT(play.play_leaves, 0u);
  EXPECT_GT(play.play_volume, 0);
  EXPECT_LT(play.play_volume, play.open_volume);  // the space high above the floors is not play
  // Every eye of a player standing on a floor is in it (cameras from another seed).
  PlayCameraConfig cams;
  cams.count = 2000;
  cams.seed = 7;
  const PlayCameras eyes = q3_play_cameras(map, scene, *caster, cams);
  size_t outside = 0;
  for (int32_t l : eyes.leaves) outside += !play.leaves[l];
  EXPECT_LE(outside, 2u) << outside << " of 2000 play cameras outside the play space";
  // One thread: the same leaves.
  tbb::task_arena one(1);
  const PlaySpace serial = one.execute([&] { return q3_play_space(map, scene, *caster, config); });
  EXPECT_EQ(serial.leaves, play.leaves);
  // Weights of the play leaves alone: the root weighs their volume.
  Subdivision q3 = q3_subdivision(map, q3_view_box(map));
  keep_leaf_weights(q3, map, play.leaves);
  EXPECT_NEAR(q3.nodes[0].weight, play.play_volume, 1e-9 * play.play_volume);
  EXPECT_THROW(keep_leaf_weights(q3, map, std::vector<bool>(3, true)), Error);
}

}  // namespace
}  // namespace viewcells
