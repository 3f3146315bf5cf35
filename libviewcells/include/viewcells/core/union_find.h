#pragma once
/// Union-find over ids 0..n-1 (path halving; the smaller id is a set's root, so the roots do
/// not depend on the order of unions).
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace viewcells {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace viewcells
