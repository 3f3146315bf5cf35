#include "support/test_scenes.h"

#include "viewcells/bsp/subdivision.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"

#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace viewcells::test {

void add_cube(RawMesh& mesh, const Vec3& lo, const Vec3& hi, const std::string& group) {
  const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
  for (int i = 0; i < 8; ++i)
    mesh.vertices.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
  // Quads with outward normals (counter-clockwise seen from outside).
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const uint32_t g = static_cast<uint32_t>(mesh.group_names.size());
  mesh.group_names.push_back(group);
  for (const auto& q : quads) {
    mesh.triangles.push_back({base + q[0], base + q[1], base + q[2]});
    mesh.triangles.push_back({base + q[0], base + q[2], base + q[3]});
    mesh.triangle_group.push_back(g);
    mesh.triangle_group.push_back(g);
  }
}

Scene cube_grid(int n, double spacing, double size) {
  RawMesh mesh;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      add_cube(mesh, {i * spacing, j * spacing, 0}, {i * spacing + size, j * spacing + size, size},
               "cube_" + std::to_string(i) + "_" + std::to_string(j));
  return make_scene(std::move(mesh), ObjectGrouping::kGroups, "cube grid");
}

std::string temp_path(const std::string& name) {
  static const std::string dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("viewcells_test_" + std::to_string(getpid()));
    // A directory of this name is a dead process's (PIDs are reused): start empty.
    std::error_code ec;
    std::filesystem::remove_all(d, ec);
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(std::filesystem::temp_directory_path() /
                                      ("viewcells_test_" + std::to_string(getpid())),
                                  ec);
    });
    return d.string();
  }();
  return dir + "/" + name;
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

SegmentSet sample_scene(const Scene& scene, uint64_t samples, uint64_t seed) {
  const auto caster = make_embree_caster(scene);
  SamplerConfig config;
  config.samples = samples;
  config.seed = seed;
  config.show_progress = false;
  return sample_segments(scene, *caster, config).segments;
}

CellLocator kd_cells(const Scene& scene, uint32_t n, uint64_t samples) {
  SubdivisionConfig sc;
  sc.strategy = SplitStrategy::kKdCycling;
  sc.max_cells = n;
  sc.show_progress = false;
  Subdivision s = subdivide(scene, sample_scene(scene, samples, 3), CostModel{}, sc);
  std::vector<int32_t> leaf_cell(s.nodes.size(), -1);
  const std::vector<int32_t> leaves = s.leaves();
  for (size_t i = 0; i < leaves.size(); ++i) leaf_cell[leaves[i]] = static_cast<int32_t>(i);
  return CellLocator(std::move(s), std::move(leaf_cell), static_cast<uint32_t>(leaves.size()));
}

std::string oa_dm2_path(const std::string& data_dir) {
  const std::string path = data_dir + "/maps/bsp/oa_dm2.bsp";
  if (std::filesystem::exists(path)) return path;
  if (std::getenv("VIEWCELLS_REQUIRE_MAPS")) ADD_FAILURE() << path << " is missing: run scripts/fetch-maps.sh";
  return "";
}

}  // namespace viewcells::test
