#pragma once
/// The built hierarchy on disk (`.vcells`): planes, nodes, split order, costs and the sampled
/// PVS of each leaf; versioned and checksummed (io/binary_file.h). Cell geometry is not stored:
/// replaying the splits from the view box rebuilds it exactly (rebuild_cells).
#include <string>
#include <vector>

#include "viewcells/bsp/cost_model.h"
#include "viewcells/bsp/subdivision.h"

namespace viewcells {

struct SubdivisionFile {
  Subdivision subdivision;                     ///< cells and segments are left empty by reading
  std::vector<std::vector<uint32_t>> leaf_pvs; ///< per node: sorted object ids (leaves only)
  CostModel cost_model;
  uint64_t scene_fingerprint = 0;
  uint32_t object_count = 0;
};

/// Sorted object ids seen by the segments of each leaf of `s`.
std::vector<std::vector<uint32_t>> leaf_pvs(const Subdivision& s, const SegmentSet& segments);

void write_subdivision(const std::string& path, const SubdivisionFile& file);
/// Reads and validates (indices, tree shape, split order); throws Error on any inconsistency.
SubdivisionFile read_subdivision(const std::string& path);

/// Recomputes the leaf polyhedra (s.cells) by replaying the splits from the view box.
void rebuild_cells(Subdivision& s);

/// Writes the leaves as a binary PLY, every cell shrunk by `shrink` towards its centre so
/// neighbours stay apart, coloured by render cost r(PVS) from blue (low) to red (high).
void write_cells_ply(const std::string& path, const Subdivision& s, double shrink = 0.97);

/// Writes a PNG of the horizontal slice z = height through the view space: each cell filled
/// with its render-cost colour, cell borders dark, and (when scene is given) the scene's
/// cross-section in black. `width` pixels along x.
void write_slice_png(const std::string& path, const Subdivision& s, double height, int width,
                     const Scene* scene = nullptr);

}  // namespace viewcells
