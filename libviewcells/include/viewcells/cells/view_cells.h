#pragma once
/// View cells and point location: the one owner of "which cell holds this point". A BSP whose
/// leaves map to view cells (a .pvs file's, or any subdivision's leaves with a leaf -> cell
/// map); the .pvs reader, the AGVS solver and the runtime reader all locate points this way.
#include <cstdint>
#include <tuple>
#include <vector>

#include "viewcells/bsp/subdivision.h"

namespace viewcells {

/// The view cell of p: the cell of the BSP leaf holding it (`leaf_cell` per node of `bsp`,
/// -1 for inner nodes), or -1 outside the view box. A point on a split plane goes to the
/// plane's negative side (Plane::side, exact).
int32_t locate_cell(const Subdivision& bsp, const std::vector<int32_t>& leaf_cell, const Vec3& p);

/// View cells for global visibility: a BSP whose leaves map to cells (a PvsFile's, or any
/// subdivision's leaves with a leaf -> cell map). Point location, the cells a segment
/// pierces, and each cell's bounds and volume (from the BSP's convex cells).
class CellLocator {
 public:
  /// `leaf_cell` per node of `bsp` (-1 for inner nodes); every leaf in a cell < cell_count.
  CellLocator(Subdivision bsp, std::vector<int32_t> leaf_cell, uint32_t cell_count);
  uint32_t cell_count() const { return cell_count_; }
  const Box3& view_box() const { return bsp_.view_box; }
  /// The cell containing p, or -1 outside the view box.
  int32_t cell_at(const Vec3& p) const;
  /// The cells the segment a-b (inside the view box) has length in, sorted, into `out`.
  void cells_of_segment(const Vec3& a, const Vec3& b, std::vector<int32_t>& out,
                        std::vector<std::tuple<int32_t, double, double>>& stack) const;
  const Box3& cell_bounds(uint32_t c) const { return bounds_[c]; }
  /// Per cell, the cells sharing a part of its boundary of positive area, sorted.
  std::vector<std::vector<uint32_t>> neighbours() const;
  double cell_volume(uint32_t c) const { return volume_[c]; }

 private:
  Subdivision bsp_;
  std::vector<int32_t> leaf_cell_;
  /// The nodes a segment's walk descends (those whose subtree holds more than one cell), depth
  /// first, a node's first child right after it: 24 bytes each. A child whose subtree lies in
  /// one cell c is named ~c, where the walk stops without reading a node.
  struct WalkNode {
    double offset = 0;
    int32_t child[2] = {-1, -1};
    int32_t axis = -1, plane = -1;
  };
  std::vector<WalkNode> walk_;
  int32_t walk_root_ = 0;  ///< the root as the walk names it (~c if it is all cell c)
  uint32_t cell_count_ = 0;
  std::vector<Box3> bounds_;
  std::vector<double> volume_;
};

}  // namespace viewcells
