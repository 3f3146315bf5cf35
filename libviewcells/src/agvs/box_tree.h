#pragma once
// AGVS paper 5 (visibility filtering): which objects' boxes an enlarged box touches, by a
// median-split tree over the objects' bounding boxes.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "viewcells/core/vec3.h"

namespace viewcells::agvs_detail {

/// Bounding boxes in a median-split tree: which boxes touch a query box.
class BoxTree {
 public:
  explicit BoxTree(std::vector<std::pair<Box3, uint32_t>> items) : items_(std::move(items)) {
    if (items_.empty()) return;
    nodes_.resize(1);
    build(0, 0, static_cast<uint32_t>(items_.size()), 0);
  }
  void query(const Box3& q, std::vector<uint32_t>& out) const {
    if (nodes_.empty()) return;
    uint32_t stack[96];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!touches(n.bounds, q)) continue;
      if (n.left == 0) {
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
          if (touches(items_[i].first, q)) out.push_back(items_[i].second);
      } else {
        stack[top++] = n.left;
        stack[top++] = n.left + 1;
      }
    }
  }

 private:
  struct Node {
    Box3 bounds;
    uint32_t left = 0, first = 0, count = 0;  ///< left: first child (the second follows); 0: a leaf
  };
  static bool touches(const Box3& a, const Box3& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
  }
  void build(uint32_t id, uint32_t first, uint32_t last, int depth) {
    Box3 b, centres;
    for (uint32_t i = first; i < last; ++i) b.extend(items_[i].first), centres.extend(items_[i].first.center());
    nodes_[id].bounds = b;
    if (last - first <= 4 || depth >= 40) {
      nodes_[id].first = first, nodes_[id].count = last - first;
      return;
    }
    const Vec3 e = centres.extent();
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const uint32_t mid = first + (last - first) / 2;
    std::nth_element(items_.begin() + first, items_.begin() + mid, items_.begin() + last,
                     [axis](const auto& p, const auto& q) { return p.first.center()[axis] < q.first.center()[axis]; });
    const uint32_t left = static_cast<uint32_t>(nodes_.size());
    nodes_.resize(left + 2);
    nodes_[id].left = left;
    build(left, first, mid, depth + 1);
    build(left + 1, mid, last, depth + 1);
  }
  std::vector<std::pair<Box3, uint32_t>> items_;
  std::vector<Node> nodes_;
};

}  // namespace viewcells::agvs_detail
