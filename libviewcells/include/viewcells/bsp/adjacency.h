#pragma once
/// Neighbouring leaves of the view space BSP: two leaves are neighbours when they share a part
/// of a split plane of positive area (view-cell-construction paper, section 4.3: the merge
/// candidates). Found per split plane from the leaves' faces on it.
#include <cstdint>
#include <vector>

#include "viewcells/bsp/subdivision.h"

namespace viewcells {

struct LeafAdjacency {
  int32_t a = -1, b = -1;  ///< node ids of the two leaves, a < b
  double area = 0;         ///< area of the shared part of their boundary, > 0
};

/// All neighbouring pairs of the current leaves, sorted by (a, b). Pairs touching in less than
/// min_relative_area * (view box diagonal)^2 (edges, corners, rounding) are left out.
std::vector<LeafAdjacency> leaf_adjacency(const Subdivision& s, double min_relative_area = 1e-12);
/// The same for the given leaves (whose cells must be built), for a BSP without split records
/// (one read from a .pvs file).
std::vector<LeafAdjacency> leaf_adjacency(const Subdivision& s, const std::vector<int32_t>& leaves,
                                          double min_relative_area = 1e-12);

}  // namespace viewcells
