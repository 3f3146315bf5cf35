#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "viewcells/core/error.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

TEST(Generators, DeterministicBySeed) {
  for (GeneratorKind kind :
       {GeneratorKind::kOffice, GeneratorKind::kCity, GeneratorKind::kRotatedOffice, GeneratorKind::kTown}) {
    const Scene a = generate_scene({kind, 11, 2});
    const Scene b = generate_scene({kind, 11, 2});
    const Scene c = generate_scene({kind, 12, 2});
    EXPECT_EQ(a.fingerprint(), b.fingerprint()) << to_string(kind);
    EXPECT_NE(a.fingerprint(), c.fingerprint()) << to_string(kind);
  }
}

TEST(Generators, ScenesAreSolid) {
  for (GeneratorKind kind :
       {GeneratorKind::kOffice, GeneratorKind::kCity, GeneratorKind::kRotatedOffice, GeneratorKind::kTown}) {
    const Scene s = generate_scene({kind, 3, kind == GeneratorKind::kTown ? 8 : 3});
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

/// The town is not a grid: its buildings face many directions, its heights vary, and at
/// size 23 it has over a million triangles.
TEST(Generators, TownHasTurnedStreetsSquaresAndTowers) {
  const Scene s = generate_scene({GeneratorKind::kTown, 1, 23});
  EXPECT_GT(s.triangle_count(), 1'000'000u);
  EXPECT_GT(s.non_axis_aligned_share(), 0.1);
  std::vector<double> angles, heights;
  int squares = 0;
  for (const ObjectInfo& o : s.objects) {
    if (o.name.find("square_") == 0) ++squares;
    if (o.name.find("_building_") == std::string::npos) continue;
    heights.push_back(o.bounds.hi.z);
  }
  // Wall directions: the angle of every vertical triangle's normal, folded into [0, 90).
  for (size_t t = 0; t < s.triangles.size(); t += 97) {
    const Vec3 a = s.vertices[s.triangles[t][0]], b = s.vertices[s.triangles[t][1]],
               c = s.vertices[s.triangles[t][2]];
    const Vec3 n = cross(b - a, c - a);
    if (std::abs(n.z) > 1e-6 * length(n)) continue;
    double deg = std::atan2(n.y, n.x) * 180 / 3.141592653589793;
    deg = std::fmod(deg + 360.0, 90.0);
    angles.push_back(std::floor(deg / 5));
  }
  std::sort(angles.begin(), angles.end());
  angles.erase(std::unique(angles.begin(), angles.end()), angles.end());
  EXPECT_GE(angles.size(), 8u) << "streets at many angles (5-degree bins of wall directions)";
  EXPECT_GT(squares, 0) << "open squares with trees";
  std::sort(heights.begin(), heights.end());
  ASSERT_GT(heights.size(), 1000u);
  EXPECT_GT(heights.back(), 100.0) << "landmark towers";
  EXPECT_GT(heights[heights.size() * 9 / 10], 2 * heights[heights.size() / 10]);
}

TEST(Generators, GlassCityIsTheCityWithSeeThroughSurfaces) {
  const Scene city = generate_scene({GeneratorKind::kCity, 2, 4});
  const Scene glass = generate_scene({GeneratorKind::kGlassCity, 2, 4});
  size_t curtains = 0, pools = 0, plain = 0;
  for (const ObjectInfo& o : glass.objects) {
    if (o.occluder) {
      ++plain;
      continue;
    }
    EXPECT_TRUE(o.solid()) << o.name;  // closed boxes, like everything generated
    curtains += o.name.ends_with("_glass");
    pools += o.name.ends_with("_water");
  }
  EXPECT_EQ(plain, city.object_count()) << "the glass is added to the city, which stays as it was";
  EXPECT_GT(curtains, 4u);
  EXPECT_GT(pools, 2u);
  EXPECT_NE(std::string(glass.source).find("glass-city"), std::string::npos);
  EXPECT_EQ(parse_generator_kind("glass-city"), GeneratorKind::kGlassCity);
}

TEST(Generators, RejectsBadParameters) {
  EXPECT_THROW(generate_scene({GeneratorKind::kCity, 1, 0}), Error);
  EXPECT_THROW(parse_generator_kind("castle"), Error);
}

}  // namespace
}  // namespace viewcells
