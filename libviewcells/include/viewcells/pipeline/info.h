#pragma once
/// `viewcells info`: what a scene holds (objects, closedness, axis alignment), and for a level
/// file what it brings besides (level/level.h: a Quake 3 map's surfaces by kind, brushes,
/// clusters, spawns).
#include <memory>
#include <string>

#include "viewcells/level/level.h"
#include "viewcells/pipeline/sampling.h"

namespace viewcells::pipeline {

struct SceneInfo {
  Scene scene;
  EmptySpaceDecision empty_space;
  size_t closed_objects = 0, solid_objects = 0;
  std::shared_ptr<const LevelData> level;  ///< what the file brings besides, or null
};

SceneInfo scene_info(const std::string& path, ObjectGrouping grouping);

}  // namespace viewcells::pipeline
