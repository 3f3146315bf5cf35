/// `viewcells info`: what a scene file holds, and on a Quake 3 map what the map brings besides.
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
  if (is_q3_map(path)) {
    // What the Quake 3 map itself holds besides the geometry.
    MapInfo m;
    m.map = read_q3bsp(path);
    q3_world_mesh(m.map, {}, &m.mesh);
    for (const Q3Leaf& l : m.map.leaves) m.solid_leaves += l.cluster < 0;
    info.map = std::move(m);
  }
  return info;
}

}  // namespace viewcells::pipeline
