/// `viewcells info`: what a scene file holds, and on a level file what it brings besides.
#include "viewcells/pipeline/info.h"

#include "viewcells/io/scene_io.h"

namespace viewcells::pipeline {

SceneInfo scene_info(const std::string& path, ObjectGrouping grouping) {
  SceneInfo info;
  info.scene = load_scene(path, grouping);
  info.empty_space = decide_empty_space(info.scene, EmptySpaceMode::kAuto);
  for (const ObjectInfo& o : info.scene.objects) {
    info.closed_objects += o.closed;
    info.solid_objects += o.solid();
  }
  info.level = read_level_data(path);  // what the file brings besides the geometry
  return info;
}

}  // namespace viewcells::pipeline
