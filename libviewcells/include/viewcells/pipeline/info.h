#pragma once
/// `viewcells info`: what a scene holds (objects, closedness, axis alignment), and for a
/// Quake 3 map what the map itself brings (surfaces by kind, brushes, clusters, spawns).
#include <optional>
#include <string>

#include "viewcells/q3/bsp_file.h"
#include "viewcells/pipeline/sampling.h"

namespace viewcells::pipeline {

struct MapInfo {
  Q3Map map;
  Q3MeshStats mesh;
  size_t solid_leaves = 0;
};

struct SceneInfo {
  Scene scene;
  EmptySpaceDecision empty_space;
  size_t closed_objects = 0, solid_objects = 0;
  std::optional<MapInfo> map;
};

SceneInfo scene_info(const std::string& path, ObjectGrouping grouping);

}  // namespace viewcells::pipeline
