#pragma once
/// A Quake 3 map's view space and its own view cells. Players stand in the map's non-solid
/// space (the leaves with a cluster), so that is the view space: sample origins are drawn
/// there, and p(i) of any view cell is the volume of its non-solid part over the non-solid
/// volume of the view box. The map compiler's BSP is turned into a Subdivision (same point
/// location, segment distribution and evaluator as our own cells), so q3map2's clusters are
/// scored on exactly the samples ours are.
#include <cstdint>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/q3/bsp_file.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// Whether p lies in the map's non-solid space: its leaf has a cluster, and no opaque brush
/// of that leaf (a detail brush) contains it. Cell weights (below) count whole leaves: detail
/// brushes take a small share of a leaf's volume.
bool q3_in_view_space(const Q3Map& map, const Vec3& p);

/// The bounding box of the non-solid leaves (Error when the map has none).
Box3 q3_view_box(const Q3Map& map);
/// The box a baked file's cells must cover: every point of a non-solid leaf that lies within
/// that leaf's bounds as the file stores them, enlarged by one unit. The file rounds bounds to
/// whole units, and q3map2 derives them from the leaf's portals, so a leaf may reach past them
/// (by a third of a unit on q3dm6ish): q3_view_box, which unites the stored bounds, misses such
/// slivers where a player can stand. Contains q3_view_box.
Box3 q3_cover_box(const Q3Map& map);

/// The map's BSP over `box` as a Subdivision: map node i is node i, map leaf l is node
/// map.nodes.size() + l (so leaf_of_node() inverts it). Q3 planes become Planes (axial ones
/// exact), each leaf's cell is the box clipped along its path, and weight is the leaf's volume
/// when it has a cluster, 0 when it is solid; inner nodes sum their children.
Subdivision q3_subdivision(const Q3Map& map, const Box3& box);
/// The map leaf of node n of a q3_subdivision (-1 for inner nodes).
inline int32_t q3_leaf_of_node(const Q3Map& map, int32_t n) {
  return n >= static_cast<int32_t>(map.nodes.size()) ? n - static_cast<int32_t>(map.nodes.size()) : -1;
}

/// Keeps the weight of the map leaves `keep` (per map leaf) of `q3` (a q3_subdivision), sets the
/// other leaves' to 0 and sums the inner nodes again: p(i) over that part of the view space
/// (such as the play space) for weight_by_view_space.
void keep_leaf_weights(Subdivision& q3, const Q3Map& map, const std::vector<bool>& keep);

/// Volume of the part of `cell` in the non-solid leaves of `q3` (a q3_subdivision).
double view_space_volume(const Subdivision& q3, const ConvexPolyhedron& cell);

/// Sets the weight of every node of `s` to the volume of its non-solid part (leaves from their
/// cells, which must be present; inner nodes as sums): p(i) over the map's view space. The
/// split records keep the costs the construction saw.
void weight_by_view_space(Subdivision& s, const Subdivision& q3);

/// q3map2's clusters as view cells, scored like ours: a cluster's PVS is the union of its
/// leaves' PVSs, its weight their non-solid volume, p(i) = weight / total weight.
struct Q3ClusterCells {
  std::vector<double> weight;                ///< per cluster
  std::vector<Box3> bounds;                  ///< per cluster (the pixel term's points)
  std::vector<std::vector<uint32_t>> pvs;    ///< per cluster: sorted object ids
  std::vector<double> pvs_cost;              ///< per cluster: r(PVS)
  double total_weight = 0;
  double cost = 0;  ///< c(S) = sum weight * pvs_cost / total_weight
};
/// `leaf_pvs` is per node of `q3` (evaluation_pvs(q3, segments)).
Q3ClusterCells q3_cluster_cells(const Scene& scene, const Q3Map& map, const Subdivision& q3,
                                const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model);

/// The map surface each rendered object of `scene` stands for (objects named
/// "shader#surface", as load_scene names a map's surfaces; -1 for objects not rendered);
/// Error when a rendered object is not one surface.
std::vector<int32_t> q3_object_surfaces(const Scene& scene, const Q3Map& map);

/// For every cluster, the objects q3map2's PVS admits: those with a surface listed in a leaf of
/// a cluster visible from it (sorted object ids). Only rendered objects are listed.
std::vector<std::vector<uint32_t>> q3_admitted_objects(const Scene& scene, const Q3Map& map);

}  // namespace viewcells
