// bake_in_memory [ROOMS]: makes a level procedurally (a grid of ROOMS x ROOMS rooms, walls with
// doorways, a crate in each room), bakes its view cells and PVSs with the whole library, and
// queries them, all in memory: no scene file is read and no .pvs written. An editor or a build
// step that holds its meshes in memory bakes this way (pipeline::bake with SceneSource::scene,
// the result in BakeResult::file).
#include <array>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>

#include <viewcells/core/error.h>
#include <viewcells/pipeline/bake.h>
#include <viewcells/pvs/pvs.h>
#include <viewcells/scene/scene.h>

namespace {

/// Appends an axis-aligned box [lo, hi] as object `name` (outward-facing triangles).
void add_box(viewcells::RawMesh& m, viewcells::Vec3 lo, viewcells::Vec3 hi, const std::string& name) {
  const uint32_t base = static_cast<uint32_t>(m.vertices.size());
  for (int i = 0; i < 8; ++i) m.vertices.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const uint32_t group = static_cast<uint32_t>(m.group_names.size());
  m.group_names.push_back(name);
  for (const auto& q : quads)
    for (const auto& t : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
      m.triangle_group.push_back(group);
    }
}

/// Rooms of 10 x 10 x 3 in a grid; every inner wall has a 2-wide doorway in its middle.
viewcells::Scene make_level(int rooms) {
  viewcells::RawMesh m;
  const double size = 10, height = 3, t = 0.2, n = rooms * size;
  add_box(m, {0, 0, -t}, {n, n, 0}, "floor");
  for (int i = 0; i <= rooms; ++i) {
    for (int j = 0; j < rooms; ++j) {
      const double a = j * size, b = a + size, door = i > 0 && i < rooms ? 1.0 : 0.0;
      const std::string id = std::to_string(i) + "_" + std::to_string(j);
      // A wall across x = i * size from y = a to b, and one across y = i * size from x = a to b,
      // each in two halves around the doorway (closed on the level's rim).
      for (int half = 0; half < 2; ++half) {
        const double lo = half ? (a + b) / 2 + door : a, hi = half ? b : (a + b) / 2 - door;
        add_box(m, {i * size - t / 2, lo, 0}, {i * size + t / 2, hi, height}, "wall_x" + id + "_" + std::to_string(half));
        add_box(m, {lo, i * size - t / 2, 0}, {hi, i * size + t / 2, height}, "wall_y" + id + "_" + std::to_string(half));
      }
    }
  }
  for (int i = 0; i < rooms; ++i)
    for (int j = 0; j < rooms; ++j)
      add_box(m, {i * size + 3, j * size + 3, 0}, {i * size + 4, j * size + 4, 1},
              "crate" + std::to_string(i) + "_" + std::to_string(j));
  return viewcells::make_scene(std::move(m), viewcells::ObjectGrouping::kGroups, "procedural level");
}

}  // namespace

int main(int argc, char** argv) {
  const int rooms = argc > 1 ? std::atoi(argv[1]) : 3;
  if (rooms < 1 || rooms > 20) {
    std::cerr << "usage: bake_in_memory [ROOMS: 1 to 20]\n";
    return 2;
  }
  try {
    viewcells::pipeline::BakeConfig config;
    config.scene.path = "procedural level";  // a name for messages: the scene is the one below
    config.scene.scene = std::make_shared<const viewcells::Scene>(make_level(rooms));
    config.cells = static_cast<uint32_t>(rooms * rooms);
    config.subdivision.max_cells = 8 * config.cells;
    config.sampling.samples = 100'000;
    config.agvs.max_samples = 200'000;
    // config.output stays empty: nothing is written; the result is in memory.
    const viewcells::pipeline::BakeResult result = viewcells::pipeline::bake(config, [](const std::string&) {});
    const viewcells::PvsFile& baked = *result.file;
    std::cout << "level: " << config.scene.scene->object_count() << " objects, "
              << config.scene.scene->triangle_count() << " triangles\n";
    std::cout << "cells: " << baked.pvs.cell_count << ", mean PVS " << result.mean_pvs << " objects, "
              << result.file_bytes << " bytes as a .pvs\n";
    for (int i = 0; i < rooms; ++i) {  // a viewer in the middle of each room of the diagonal
      const viewcells::Vec3 eye{i * 10.0 + 5, i * 10.0 + 5, 1.7};
      const int32_t cell = baked.locate(eye);
      std::cout << "room " << i << " " << i << ": cell " << cell << " sees "
                << (cell >= 0 ? baked.pvs.cell_pvs(static_cast<uint32_t>(cell)).size() : 0) << " objects\n";
    }
  } catch (const viewcells::Error& e) {
    std::cerr << "bake_in_memory: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
