// Extraction (view-cell-construction paper, section 5.1): the view cells of a merge history
// cut by a count, by a memory budget for their PVSs, or by a render-cost ratio.
#include "viewcells/merge/merge.h"

#include <cmath>
#include <string>
#include <utility>

#include "viewcells/core/error.h"

namespace viewcells {

namespace {

ViewCellSet make_set(const MergeHistory& h, size_t k, std::string rule) {
  ViewCellSet set;
  set.cells = h.cut_after(k);
  set.cost = h.cost_with(h.leaf_count - k);
  for (int32_t c : set.cells) {
    set.pvs_entries += h.nodes[c].pvs_size;
    set.pvs_bytes += approx_pvs_bytes(h.nodes[c].pvs_size);
  }
  set.rule = std::move(rule);
  return set;
}

}  // namespace

ViewCellSet extract_by_count(const MergeHistory& h, size_t count) {
  if (count < h.min_cells() || count > h.leaf_count)
    throw Error("cannot extract " + std::to_string(count) + " cells: the merge history holds " +
                std::to_string(h.min_cells()) + " to " + std::to_string(h.leaf_count));
  return make_set(h, h.leaf_count - count, "exactly " + std::to_string(count) + " cells");
}

ViewCellSet extract_by_memory(const MergeHistory& h, uint64_t bytes) {
  // Start from the coarsest cut and undo merges, the last first, while the budget allows.
  size_t k = h.merges();
  uint64_t used = 0;
  for (int32_t c : h.cut_after(k)) used += approx_pvs_bytes(h.nodes[c].pvs_size);
  if (used > bytes)
    throw Error("a PVS budget of " + std::to_string(bytes) + " bytes is too small: the coarsest " +
                std::to_string(h.min_cells()) + " cell(s) need " + std::to_string(used));
  while (k > 0) {
    const MergeNode& m = h.nodes[h.leaf_count + k - 1];
    const uint64_t next = used - approx_pvs_bytes(m.pvs_size) + approx_pvs_bytes(h.nodes[m.child[0]].pvs_size) +
                          approx_pvs_bytes(h.nodes[m.child[1]].pvs_size);
    if (next > bytes) break;
    used = next;
    --k;
  }
  ViewCellSet set = make_set(h, k, "most cells within " + std::to_string(bytes) + " bytes of PVS");
  VC_CHECK(set.pvs_bytes == used);
  return set;
}

ViewCellSet extract_by_cost_ratio(const MergeHistory& h, double ratio) {
  if (!(ratio >= 1.0) || !std::isfinite(ratio)) throw Error("the cost ratio must be a number >= 1");
  const double limit = ratio * h.initial_cost;
  size_t k = 0;  // the most merges whose cost stays within the limit
  for (size_t j = 1; j <= h.merges(); ++j)
    if (h.cost_after[j - 1] <= limit) k = j;
  return make_set(h, k, "fewest cells within " + std::to_string(ratio) + " x the cost of the elementary cells");
}

}  // namespace viewcells
