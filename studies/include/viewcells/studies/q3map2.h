#pragma once
/// Our view cells against q3map2's on a Quake 3 map: render cost at equal cell counts, PVS
/// agreement per cluster, and storage. Everything runs on the map's view space (its
/// non-solid leaves): sample origins, cell weights, and the evaluation of both methods on the
/// same evaluation segments.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "viewcells/studies/methods.h"
#include "viewcells/q3/view_space.h"

namespace viewcells {

/// An object our samples see from a cluster that q3map2's PVS does not admit, with the first
/// evaluation segment that saw it and why.
struct Q3Excluded {
  int32_t cluster = -1;
  uint32_t object = 0;
  size_t segment = 0;
  /// The segment crosses the map's solid space:
  ///  - "crack": it enters and leaves a brush through drawn sides, so it slipped through a
  ///    drawn surface (a crack between triangles, a gap at a T-junction);
  ///  - "invisible": it enters or leaves a brush through a side that is not drawn (caulk,
  ///    clip, an invisible wall): solid for q3map2's vis, open to the eye;
  ///  - "void": in solid space no brush fills: space q3map2 filled as outside the map.
  /// The segment stays in non-solid space:
  ///  - "unlisted": the object is seen in a cluster q3map2 admits, but the map does not list
  ///    its surface in that cluster's leaves;
  ///  - "far": the object lies beyond the map's "_farplanedist" from the cluster, and q3map2
  ///    culls far clusters on purpose (the engine fogs them out);
  ///  - "rejected": a line of sight that q3map2's PVS rejects (a q3map2 omission).
  std::string cause;
};

struct Q3Comparison {
  Comparison ours;          ///< the methods compared (AV-M at least), on the map's view space
  Q3ClusterCells clusters;  ///< q3map2's clusters, evaluated
  uint32_t cluster_count = 0;
  // Render cost.
  double avm_cost_at_clusters = 0;   ///< AV-M's evaluated c(S) at cluster_count cells (NaN: not reached)
  uint32_t avm_cells_to_match = 0;   ///< fewest AV-M cells with c(S) <= q3map2's (0: none up to max)
  // PVS agreement over the clusters with a non-empty q3map2 PVS.
  double mean_pvs_ratio = 0;         ///< mean of |ours| / |q3map2| (rendered objects)
  uint64_t ours_entries = 0, q3_entries = 0;
  std::vector<Q3Excluded> excluded;  ///< every (cluster, object) pair we see and q3map2 excludes
  std::map<std::string, uint64_t> excluded_by_cause;
  // Storage.
  uint64_t q3_row_bytes = 0;            ///< q3map2's uncompressed cluster rows
  uint64_t q3_leaf_surface_bytes = 0;   ///< the leaf -> surface lists the renderer also needs
  uint64_t ours_compressed_bytes = 0;   ///< AV-M cells at cluster_count: hierarchy-compressed lists (as the .pvs codes them)
  uint64_t ours_rle_bytes = 0;          ///< the same cells as Quake-style RLE object rows
  double build_seconds = 0;             ///< AV-S + merging
};

/// Compares config.methods (which must include av-m) with q3map2's clusters. Sets the view
/// space of both samplers and the view box to the map's (unless config gives a box), and
/// weights every subdivision by the view space. config.max_cells = 0: three times the
/// cluster count.
Q3Comparison compare_with_q3map2(const Scene& scene, const Q3Map& map, const RayCaster& caster, CompareConfig config);

}  // namespace viewcells
