/// Point location: which view cell holds a point, for .pvs files, the AGVS solver and any
/// subdivision.
#include "viewcells/cells/view_cells.h"

#include <algorithm>

#include "bsp/segment_walk.h"
#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"

namespace viewcells {

int32_t locate_cell(const Subdivision& bsp, const std::vector<int32_t>& leaf_cell, const Vec3& p) {
  const int32_t leaf = bsp.locate(p);
  return leaf < 0 ? -1 : leaf_cell[leaf];
}

CellLocator::CellLocator(Subdivision bsp, std::vector<int32_t> leaf_cell, uint32_t cell_count)
    : bsp_(std::move(bsp)), leaf_cell_(std::move(leaf_cell)), cell_count_(cell_count) {
  if (bsp_.nodes.empty() || leaf_cell_.size() != bsp_.nodes.size()) throw Error("the view cells need a BSP");
  if (cell_count_ == 0) throw Error("there are no view cells");
  for (size_t n = 0; n < bsp_.nodes.size(); ++n)
    if (bsp_.nodes[n].plane < 0 && (leaf_cell_[n] < 0 || leaf_cell_[n] >= static_cast<int32_t>(cell_count_)))
      throw Error("BSP leaf " + std::to_string(n) + " has no view cell");
  bounds_.assign(cell_count_, Box3{});
  volume_.assign(cell_count_, 0.0);
  clip_to_leaves(bsp_, ConvexPolyhedron::box(bsp_.view_box, 0), [&](int32_t n, const ConvexPolyhedron& part) {
    bounds_[leaf_cell_[n]].extend(part.bounds());
    volume_[leaf_cell_[n]] += part.volume();
  });
  for (uint32_t c = 0; c < cell_count_; ++c)
    if (!(volume_[c] > 0)) throw Error("view cell " + std::to_string(c) + " has no volume");
  // The tree as segments walk it, compactly: the cell of each node's whole subtree, or -1
  // (children first), then the nodes with -1 in depth-first order, per node its plane's axis
  // and offset (or the plane itself, for the few that are not axis-aligned) and its children.
  std::vector<int32_t> cell(bsp_.nodes.size(), -1);
  std::vector<std::pair<int32_t, bool>> stack{{0, false}};
  while (!stack.empty()) {
    const auto [n, children_done] = stack.back();
    stack.pop_back();
    const BspNode& node = bsp_.nodes[n];
    if (node.plane < 0) {
      cell[n] = leaf_cell_[n];
    } else if (children_done) {
      const int32_t c0 = cell[node.child[0]], c1 = cell[node.child[1]];
      cell[n] = c0 >= 0 && c0 == c1 ? c0 : -1;
    } else {
      stack.push_back({n, true});
      stack.push_back({node.child[0], false});
      stack.push_back({node.child[1], false});
    }
  }
  std::vector<int32_t> id(bsp_.nodes.size()), order;
  std::vector<int32_t> todo{0};
  while (!todo.empty()) {
    const int32_t n = todo.back();
    todo.pop_back();
    if (cell[n] >= 0) {
      id[n] = ~cell[n];
      continue;
    }
    id[n] = static_cast<int32_t>(order.size());
    order.push_back(n);
    todo.push_back(bsp_.nodes[n].child[1]);
    todo.push_back(bsp_.nodes[n].child[0]);
  }
  walk_root_ = id[0];
  walk_.assign(order.size(), WalkNode{});
  for (size_t i = 0; i < order.size(); ++i) {
    const BspNode& node = bsp_.nodes[order[i]];
    const Plane& plane = bsp_.planes[node.plane];
    WalkNode& w = walk_[i];
    w.axis = plane.axis;
    w.offset = plane.offset;
    w.plane = node.plane;
    w.child[0] = id[node.child[0]];
    w.child[1] = id[node.child[1]];
  }
}

int32_t CellLocator::cell_at(const Vec3& p) const { return locate_cell(bsp_, leaf_cell_, p); }

void CellLocator::cells_of_segment(const Vec3& a, const Vec3& b, std::vector<int32_t>& out,
                                   std::vector<std::tuple<int32_t, double, double>>& stack) const {
  out.clear();
  struct Tree {
    const std::vector<WalkNode>& walk;
    const std::vector<Plane>& planes;
    int axis(int32_t n) const { return walk[n].axis; }
    double offset(int32_t n) const { return walk[n].offset; }
    const Plane& plane(int32_t n) const { return planes[walk[n].plane]; }
    int32_t child(int32_t n, int k) const { return walk[n].child[k]; }
  };
  bsp_detail::walk_segment(
      Tree{walk_, bsp_.planes}, a, b, stack,
      [&](int32_t n, double, double) {
        if (n >= 0) return false;
        out.push_back(~n);
        return true;
      },
      walk_root_);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::vector<std::vector<uint32_t>> CellLocator::neighbours() const {
  std::vector<std::vector<uint32_t>> out(cell_count_);
  // The leaves' convex cells (a BSP read from a file has none), replayed from the view box.
  Subdivision with_cells = bsp_;
  with_cells.cells.assign(bsp_.nodes.size(), ConvexPolyhedron());
  clip_to_leaves(bsp_, ConvexPolyhedron::box(bsp_.view_box, 0),
                 [&](int32_t n, const ConvexPolyhedron& part) { with_cells.cells[n] = part; });
  std::vector<int32_t> leaves;
  for (size_t n = 0; n < bsp_.nodes.size(); ++n)
    if (bsp_.nodes[n].plane < 0) leaves.push_back(static_cast<int32_t>(n));
  for (const LeafAdjacency& a : leaf_adjacency(with_cells, leaves)) {
    const int32_t ca = leaf_cell_[a.a], cb = leaf_cell_[a.b];
    if (ca == cb) continue;
    out[ca].push_back(static_cast<uint32_t>(cb));
    out[cb].push_back(static_cast<uint32_t>(ca));
  }
  for (auto& list : out) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return out;
}

}  // namespace viewcells
