#include <gtest/gtest.h>

#include <algorithm>

#include "viewcells/core/error.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

TEST(Generators, DeterministicBySeed) {
  for (GeneratorKind kind : {GeneratorKind::kOffice, GeneratorKind::kCity, GeneratorKind::kRotatedOffice}) {
    const Scene a = generate_scene({kind, 11, 2});
    const Scene b = generate_scene({kind, 11, 2});
    const Scene c = generate_scene({kind, 12, 2});
    EXPECT_EQ(a.fingerprint(), b.fingerprint()) << to_string(kind);
    EXPECT_NE(a.fingerprint(), c.fingerprint()) << to_string(kind);
  }
}

TEST(Generators, ScenesAreSolid) {
  for (GeneratorKind kind : {GeneratorKind::kOffice, GeneratorKind::kCity, GeneratorKind::kRotatedOffice}) {
    const Scene s = generate_scene({kind, 3, 3});
    EXPECT_TRUE(s.all_solid) << to_string(kind);
    EXPECT_EQ(s.degenerate_dropped, 0u);
    for (const ObjectInfo& o : s.objects) EXPECT_TRUE(o.solid()) << o.name;
  }
}

TEST(Generators, OfficeHasRoomsDoorsStairsAndFurniture) {
  const Scene s = generate_scene({GeneratorKind::kOffice, 1, 4});  // two floors
  auto count = [&](const std::string& part) {
    return std::count_if(s.objects.begin(), s.objects.end(),
                         [&](const ObjectInfo& o) { return o.name.find(part) != std::string::npos; });
  };
  EXPECT_EQ(count("_doorwall"), 2 * 2 * 5);  // floors x sides x rooms
  EXPECT_EQ(count("_stairs"), 1);
  EXPECT_GT(count("_desk"), 5);
  EXPECT_GT(count("_chair"), 3);
  EXPECT_EQ(s.non_axis_aligned_share(), 0.0);
  EXPECT_GT(s.bounds.extent().z, 6.0);
}

TEST(Generators, SizeScalesTriangles) {
  EXPECT_LT(generate_scene({GeneratorKind::kOffice, 1, 1}).triangle_count(), 1500u);
  EXPECT_LT(generate_scene({GeneratorKind::kCity, 1, 1}).triangle_count(), 5000u);
  const Scene city = generate_scene({GeneratorKind::kCity, 1, 6});
  EXPECT_GT(city.triangle_count(), 50000u);
  EXPECT_GT(city.object_count(), 400u);
}

TEST(Generators, CityHeightsVaryStrongly) {
  const Scene s = generate_scene({GeneratorKind::kCity, 5, 6});
  std::vector<double> heights;
  for (const ObjectInfo& o : s.objects)
    if (o.name.find("_building_") != std::string::npos) heights.push_back(o.bounds.hi.z);
  ASSERT_GT(heights.size(), 100u);
  std::sort(heights.begin(), heights.end());
  const double median = heights[heights.size() / 2];
  EXPECT_GT(heights.back(), 3 * median) << "towers rise well above the typical roof";
  EXPECT_LT(heights.front(), 0.7 * median);
}

TEST(Generators, RotatedOfficeIsNotAxisAligned) {
  const Scene s = generate_scene({GeneratorKind::kRotatedOffice, 1, 2});
  EXPECT_GT(s.non_axis_aligned_share(), 0.3);
  EXPECT_LT(s.non_axis_aligned_share(), 0.9);  // floors and ceilings stay horizontal
  const Scene o = generate_scene({GeneratorKind::kOffice, 1, 2});
  EXPECT_EQ(s.triangle_count(), o.triangle_count());
}

TEST(Generators, RejectsBadParameters) {
  EXPECT_THROW(generate_scene({GeneratorKind::kCity, 1, 0}), Error);
  EXPECT_THROW(parse_generator_kind("castle"), Error);
}

}  // namespace
}  // namespace viewcells
