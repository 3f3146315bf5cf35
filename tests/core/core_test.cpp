#include <gtest/gtest.h>

#include <set>

#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/rng.h"
#include "viewcells/core/vec3.h"

namespace viewcells {
namespace {

TEST(ErrorMessage, CarriesFileAndLine) {
  const Error e("scene.obj", 12, "bad vertex");
  EXPECT_STREQ(e.what(), "scene.obj:12: bad vertex");
  EXPECT_EQ(e.file(), "scene.obj");
  EXPECT_EQ(e.line(), 12);
  EXPECT_STREQ(Error("scene.obj", 0, "missing").what(), "scene.obj: missing");
}

TEST(Rng, StreamsAreReproducibleAndDistinct) {
  Rng a(5, 3), b(5, 3), c(5, 4), d(6, 3);
  std::set<uint64_t> firsts;
  for (int i = 0; i < 100; ++i) {
    const uint64_t x = a.next_u64();
    EXPECT_EQ(x, b.next_u64());
    firsts.insert(x);
  }
  EXPECT_NE(Rng(5, 3).next_u64(), c.next_u64());
  EXPECT_NE(Rng(5, 3).next_u64(), d.next_u64());
  EXPECT_EQ(firsts.size(), 100u);
}

TEST(Rng, UniformIsInRangeWithTheRightMean) {
  Rng r(1);
  double sum = 0;
  for (int i = 0; i < 100000; ++i) {
    const double u = r.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
  }
  EXPECT_NEAR(sum / 100000, 0.5, 0.005);
}

TEST(Box, ClipLineToBox) {
  const Box3 b{{0, 0, 0}, {2, 1, 1}};
  double t0, t1;
  ASSERT_TRUE(clip_line_to_box(b, {1, 0.5, 0.5}, {1, 0, 0}, t0, t1));
  EXPECT_DOUBLE_EQ(t0, -1.0);
  EXPECT_DOUBLE_EQ(t1, 1.0);
  // Axis-parallel line outside the slab of a zero direction component.
  EXPECT_FALSE(clip_line_to_box(b, {1, 2, 0.5}, {1, 0, 0}, t0, t1));
  // Diagonal line through a corner region.
  ASSERT_TRUE(clip_line_to_box(b, {0, 0, 0}, {1, 1, 1}, t0, t1));
  EXPECT_DOUBLE_EQ(t0, 0.0);
  EXPECT_DOUBLE_EQ(t1, 1.0);
  EXPECT_FALSE(clip_line_to_box(b, {3, 3, 3}, {1, 1, 0}, t0, t1));
}

TEST(Box, EmptyAndVolume) {
  Box3 b;
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b.volume(), 0.0);
  b.extend({1, 2, 3});
  b.extend({2, 4, 6});
  EXPECT_FALSE(b.empty());
  EXPECT_DOUBLE_EQ(b.volume(), 6.0);
  EXPECT_TRUE(b.contains({1.5, 3, 4}));
  EXPECT_FALSE(b.contains({0.9, 3, 4}));
  EXPECT_TRUE(b.contains({0.9, 3, 4}, 0.2));
}

TEST(ThreadLimit, ReportsThreads) {
  ThreadLimit one(1);
  EXPECT_EQ(one.threads(), 1);
  ThreadLimit all(0);
  EXPECT_EQ(all.threads(), hardware_threads());
}

}  // namespace
}  // namespace viewcells
