#include <gtest/gtest.h>

#include <fstream>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/sampling/segments.h"

namespace viewcells {
namespace {

SegmentSet small_set() {
  SegmentSet s;
  s.view_box = {{0, 0, 0}, {10, 10, 10}};
  s.push_back({1, 2, 3}, {4, 5, 6}, 0, kNoObject, 7, kNoObject);
  s.push_back({0, 0, 0}, {10, 10, 10}, 2, 1, 8, 9);
  s.push_back({1.0 / 3, 2, 3}, {9, 9, 9}, kNoObject, 2, kNoObject, 10);
  return s;
}

TEST(SegmentFile, RoundTrip) {
  const std::string path = test::temp_path("s.vseg");
  SegmentFileHeader h;
  h.seed = 42;
  h.samples = 10;
  h.scene_fingerprint = 0x1234;
  h.object_count = 3;
  h.empty_space_detection = true;
  write_segments(path, small_set(), h);
  SegmentFileHeader back;
  const SegmentSet s = read_segments(path, &back);
  EXPECT_TRUE(s == small_set());
  EXPECT_EQ(back.seed, 42u);
  EXPECT_EQ(back.samples, 10u);
  EXPECT_EQ(back.scene_fingerprint, 0x1234u);
  EXPECT_EQ(back.object_count, 3u);
  EXPECT_TRUE(back.empty_space_detection);
}

TEST(SegmentFile, SampledSegmentsRoundTrip) {
  const Scene scene = test::cube_grid(3);
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = 5000;
  config.show_progress = false;
  const SamplingResult r = sample_segments(scene, *caster, config);
  const std::string path = test::temp_path("sampled.vseg");
  write_segments(path, r.segments, {1, 5000, scene.fingerprint(), static_cast<uint32_t>(scene.object_count()), true});
  EXPECT_TRUE(read_segments(path) == r.segments);
}

TEST(SegmentFile, InconsistentContentIsRejected) {
  const std::string path = test::temp_path("bad_objects.vseg");
  SegmentFileHeader h;
  h.object_count = 2;  // the set names object 2
  write_segments(path, small_set(), h);
  EXPECT_THROW(read_segments(path), Error);

  SegmentSet outside = small_set();
  outside.ax[0] = 11;  // beyond the view box
  const std::string path2 = test::temp_path("outside.vseg");
  h.object_count = 3;
  write_segments(path2, outside, h);
  EXPECT_THROW(read_segments(path2), Error);

  const std::string path3 = test::temp_path("truncated.vseg");
  write_segments(path3, small_set(), h);
  std::ifstream in(path3, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  test::write_file(path3, bytes.substr(0, bytes.size() - 3));
  try {
    read_segments(path3);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace viewcells
