/// A Quake 3 map's solid space for proving objects hidden (q3/hidden.h; issue 65): the map
/// compiler's BSP as it is, so that the portals are those q3map2's vis flooded.
#include "viewcells/q3/hidden.h"

#include "viewcells/core/error.h"
#include "viewcells/q3/view_space.h"

namespace viewcells {

SolidBsp q3_solid_bsp(const Q3Map& map, const Scene& scene) {
  if (map.nodes.empty() || map.leaves.empty()) throw Error(map.path, 0, "the map has no BSP to find portals in");
  SolidBsp b;
  b.planes.reserve(map.planes.size());
  for (const Q3Plane& p : map.planes) b.planes.push_back({p.normal, p.dist});
  b.nodes.reserve(map.nodes.size());
  for (const Q3Node& n : map.nodes) b.nodes.push_back({n.plane, {n.children[0], n.children[1]}});
  b.leaf_solid.reserve(map.leaves.size());
  for (const Q3Leaf& l : map.leaves) b.leaf_solid.push_back(l.cluster < 0 ? 1 : 0);
  Box3 box = scene.bounds;
  box.extend(q3_cover_box(map));
  const double margin = 64;
  box.lo = box.lo - Vec3{margin, margin, margin};
  box.hi = box.hi + Vec3{margin, margin, margin};
  b.bounds = box;
  // q3map2 keeps its planes as floats (a face of the map found 4e-4 units off its node's
  // plane at 600 units out): a surface within its ON_EPSILON, 0.1, of a plane is on it.
  b.surface_slack = 0.1;
  return b;
}

std::shared_ptr<const HiddenSpace> q3_hidden_space(const Q3Map& map, const Scene& scene) {
  return bsp_hidden_space(q3_solid_bsp(map, scene), scene, "the map's BSP (" + map.path + ")", q3_spawn_points(map));
}

}  // namespace viewcells
