#pragma once
/// The built view cell hierarchy on disk (`.vcells`): the subdivision's planes, nodes, split
/// order and costs, the sampled PVS of each leaf and the merge history over the leaves;
/// versioned and checksummed (core/binary_file.h). Cell geometry is not stored: replaying the
/// splits from the view box rebuilds it exactly (bsp/subdivision.h, rebuild_cells).
#include <optional>
#include <string>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/merge/merge.h"

namespace viewcells {

struct SubdivisionFile {
  Subdivision subdivision;                     ///< cells and segments are left empty by reading
  std::vector<std::vector<uint32_t>> leaf_pvs; ///< per node: sorted object ids (leaves only)
  CostModel cost_model;
  uint64_t scene_fingerprint = 0;
  uint32_t object_count = 0;
  /// The merge history over the leaves (MHT leaf i is subdivision.leaves()[i]), if merged.
  std::optional<MergeHistory> history;
  std::vector<std::string> object_names;  ///< one per object (empty in version 1 and 2 files)
};

void write_subdivision(const std::string& path, const SubdivisionFile& file);
/// Reads and validates (indices, tree shape, split order); throws Error on any inconsistency.
SubdivisionFile read_subdivision(const std::string& path);

}  // namespace viewcells
