#pragma once
/// The built hierarchy on disk (`.vcells`): planes, nodes, split order, costs and the sampled
/// PVS of each leaf; versioned and checksummed (io/binary_file.h). Cell geometry is not stored:
/// replaying the splits from the view box rebuilds it exactly (rebuild_cells).
#include <optional>
#include <string>
#include <vector>

#include "viewcells/bsp/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/io/binary_file.h"
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

/// Pieces of the hierarchy file that the .pvs file shares: the split planes (count, then
/// axis, normal, offset and defining points of each), and a validated view box.
void put_planes(ByteWriter& w, const std::vector<Plane>& planes);
std::vector<Plane> get_planes(ByteReader& r, uint64_t max_items);
Box3 get_view_box(ByteReader& r);

/// Sorted object ids seen by the segments of each leaf of `s`.
std::vector<std::vector<uint32_t>> leaf_pvs(const Subdivision& s, const SegmentSet& segments);

void write_subdivision(const std::string& path, const SubdivisionFile& file);
/// Reads and validates (indices, tree shape, split order); throws Error on any inconsistency.
SubdivisionFile read_subdivision(const std::string& path);

/// Recomputes the leaf polyhedra (s.cells) by replaying the splits from the view box.
void rebuild_cells(Subdivision& s);

/// How the views below draw the leaves when they show larger cells (e.g. extracted ones):
/// per BSP node, the value its colour comes from and the cell it belongs to.
struct CellView {
  std::vector<double> value;   ///< per node (leaves); colour from blue (low) to red (high)
  std::vector<int32_t> group;  ///< per node (leaves); borders are drawn between groups
};
/// The view of a set of merged cells: every leaf coloured by the r(PVS) of its cell.
CellView merged_cell_view(const Subdivision& s, const MergeHistory& h, const std::vector<int32_t>& cells);

/// Writes the leaves as a binary PLY, every leaf shrunk by `shrink` towards its centre so
/// neighbours stay apart, coloured by render cost r(PVS) from blue (low) to red (high), or by
/// `view` when given.
void write_cells_ply(const std::string& path, const Subdivision& s, const CellView* view = nullptr,
                     double shrink = 0.97);

/// Writes a PNG of the horizontal slice z = height through the view space: each cell filled
/// with its render-cost colour, cell borders dark, and (when scene is given) the scene's
/// cross-section in black. `width` pixels along x. `view` as for write_cells_ply.
void write_slice_png(const std::string& path, const Subdivision& s, double height, int width,
                     const Scene* scene = nullptr, const CellView* view = nullptr);

}  // namespace viewcells
