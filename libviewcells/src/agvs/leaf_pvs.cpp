// The leaves' PVSs of a subdivision by AGVS: what merging decides on (view-cell-construction
// paper 4.3 needs the PVS of every elementary cell; the construction samples give a few
// hundred segments per leaf, and greedy merging fits their gaps).
#include <algorithm>

#include "viewcells/agvs/agvs.h"
#include "viewcells/core/error.h"

namespace viewcells {

LeafPvsRun leaf_pvs_by_agvs(const Scene& scene, const RayCaster& caster, const Subdivision& s,
                            const AgvsConfig& config, const std::vector<std::vector<uint32_t>>& base) {
  if (!base.empty() && base.size() != s.nodes.size()) throw Error("leaf PVSs do not match the subdivision");
  const std::vector<int32_t> leaves = s.leaves();
  std::vector<int32_t> leaf_cell(s.nodes.size(), -1);
  for (size_t i = 0; i < leaves.size(); ++i) leaf_cell[leaves[i]] = static_cast<int32_t>(i);
  Subdivision bsp;  // the tree alone: the locator needs neither cells nor segments
  bsp.view_box = s.view_box;
  bsp.planes = s.planes;
  bsp.nodes = s.nodes;
  const CellLocator cells(std::move(bsp), std::move(leaf_cell), static_cast<uint32_t>(leaves.size()));
  AgvsSolver solver(scene, caster, cells, config);
  solver.run();
  LeafPvsRun out;
  out.stats = solver.stats();
  out.pvs.resize(s.nodes.size());
  const GlobalPvs& pvs = solver.pvs();
  for (size_t i = 0; i < leaves.size(); ++i) {
    std::vector<uint32_t> found = pvs.list(static_cast<uint32_t>(i));
    std::vector<uint32_t>& dst = out.pvs[leaves[i]];
    if (base.empty()) {
      dst = std::move(found);
    } else {
      const std::vector<uint32_t>& b = base[leaves[i]];
      dst.reserve(b.size() + found.size());
      std::set_union(b.begin(), b.end(), found.begin(), found.end(), std::back_inserter(dst));
    }
  }
  return out;
}

}  // namespace viewcells
