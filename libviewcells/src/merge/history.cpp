// Where merging starts and what its history answers (view-cell-construction paper, section
// 4.3): cell partitions from a subdivision or a grid, the merges of a subdivision read as a
// history, blocks of a subdivision's cut, and a merge history's cost, cuts and leaves.
#include "viewcells/merge/merge.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <iterator>
#include <limits>
#include <optional>
#include <type_traits>

#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"

namespace viewcells {

CellPartition partition_from_subdivision(const Subdivision& s, const std::vector<std::vector<uint32_t>>& leaf_pvs) {
  std::vector<std::vector<uint32_t>> copy = leaf_pvs;
  return partition_from_subdivision(s, std::move(copy));
}

CellPartition partition_from_subdivision(const Subdivision& s, std::vector<std::vector<uint32_t>>&& leaf_pvs) {
  const std::vector<int32_t> leaves = s.leaves();
  if (s.cells.size() != s.nodes.size()) throw Error("the subdivision's cells are missing (rebuild them first)");
  if (leaf_pvs.size() != s.nodes.size()) throw Error("leaf PVSs do not match the subdivision");
  CellPartition p;
  std::vector<int32_t> index(s.nodes.size(), -1);
  for (size_t i = 0; i < leaves.size(); ++i) {
    const int32_t n = leaves[i];
    index[n] = static_cast<int32_t>(i);
    p.weight.push_back(s.nodes[n].weight);
    p.volume.push_back(s.nodes[n].volume);
    p.bounds.push_back(s.cells[n].bounds());
    p.pvs.push_back(std::move(leaf_pvs[n]));
  }
  for (const LeafAdjacency& a : leaf_adjacency(s)) {
    const uint32_t x = index[a.a], y = index[a.b];
    p.neighbours.emplace_back(std::min(x, y), std::max(x, y));
  }
  std::sort(p.neighbours.begin(), p.neighbours.end());
  return p;
}

std::vector<std::pair<int32_t, int32_t>> subdivision_prefix(const Subdivision& s, size_t cells) {
  const std::vector<int32_t> leaves = s.leaves();
  std::vector<int32_t> mht(s.nodes.size(), -1);  // BSP node -> MHT node, once it is a cell
  for (size_t i = 0; i < leaves.size(); ++i) mht[leaves[i]] = static_cast<int32_t>(i);
  std::vector<std::pair<int32_t, int32_t>> prefix;
  int32_t next = static_cast<int32_t>(leaves.size());
  for (size_t k = s.splits.size(); k-- > 0 && leaves.size() - prefix.size() > std::max<size_t>(cells, 1);) {
    const int32_t node = s.splits[k].node, c0 = s.nodes[node].child[0], c1 = s.nodes[node].child[1];
    VC_CHECK(mht[c0] >= 0 && mht[c1] >= 0);
    prefix.emplace_back(mht[c0], mht[c1]);
    mht[node] = next++;
  }
  return prefix;
}

std::vector<std::pair<int32_t, int32_t>> merges_by_least_leaf(const MergeHistory& h) {
  std::vector<int32_t> least(h.nodes.size());
  for (size_t n = 0; n < h.leaf_count; ++n) least[n] = static_cast<int32_t>(n);
  std::vector<std::pair<int32_t, int32_t>> out;
  for (size_t k = h.leaf_count; k < h.nodes.size(); ++k) {
    const int32_t a = least[h.nodes[k].child[0]], b = least[h.nodes[k].child[1]];
    least[k] = std::min(a, b);
    out.emplace_back(a, b);
  }
  return out;
}

std::vector<std::pair<int32_t, int32_t>> least_leaf_merges_as_prefix(
    const std::vector<std::pair<int32_t, int32_t>>& merges, size_t leaves) {
  std::vector<int32_t> node(leaves);
  for (size_t n = 0; n < leaves; ++n) node[n] = static_cast<int32_t>(n);
  std::vector<std::pair<int32_t, int32_t>> out;
  int32_t next = static_cast<int32_t>(leaves);
  for (const auto& [a, b] : merges) {
    if (a < 0 || b < 0 || static_cast<size_t>(a) >= leaves || static_cast<size_t>(b) >= leaves || a == b)
      throw Error("a merge names a cell by a leaf that is not one (" + std::to_string(a) + ", " + std::to_string(b) + ")");
    out.emplace_back(node[a], node[b]);
    node[std::min(a, b)] = next++;
  }
  return out;
}

std::vector<int32_t> subdivision_blocks(const Subdivision& s, size_t cells) {
  const std::vector<int32_t> leaves = s.leaves();
  std::vector<int32_t> block_of(s.nodes.size(), -1);
  for (int32_t n : s.leaves_after(std::max<size_t>(cells, 1) - 1)) block_of[n] = n;
  // Nodes are created parent first: a node without a block inherits its parent's.
  for (size_t n = 0; n < s.nodes.size(); ++n)
    if (block_of[n] < 0 && s.nodes[n].parent >= 0) block_of[n] = block_of[s.nodes[n].parent];
  std::vector<int32_t> out(leaves.size());
  for (size_t i = 0; i < leaves.size(); ++i) out[i] = block_of[leaves[i]];
  return out;
}

CellPartition grid_partition(const SegmentSet& segs, int nx, int ny, int nz) {
  if (nx < 1 || ny < 1 || nz < 1) throw Error("a grid needs at least one cell along each axis");
  const Box3 box = segs.view_box;
  if (!(box.volume() > 0)) throw Error("the segments' view box has no volume");
  const int n[3] = {nx, ny, nz};
  const Vec3 e = box.extent();
  auto cell_box = [&](int i, int j, int k) {
    const int c[3] = {i, j, k};
    Box3 b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = box.lo[a] + e[a] * c[a] / n[a];
      b.hi[a] = c[a] + 1 == n[a] ? box.hi[a] : box.lo[a] + e[a] * (c[a] + 1) / n[a];
    }
    return b;
  };
  auto index = [&](int i, int j, int k) { return static_cast<uint32_t>((k * ny + j) * nx + i); };
  CellPartition p;
  const size_t cells = static_cast<size_t>(nx) * ny * nz;
  p.weight.resize(cells);
  p.volume.resize(cells);
  p.bounds.resize(cells);
  p.pvs.resize(cells);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const uint32_t c = index(i, j, k);
        p.bounds[c] = cell_box(i, j, k);
        p.volume[c] = p.weight[c] = p.bounds[c].volume();
        if (i + 1 < nx) p.neighbours.emplace_back(c, index(i + 1, j, k));
        if (j + 1 < ny) p.neighbours.emplace_back(c, index(i, j + 1, k));
        if (k + 1 < nz) p.neighbours.emplace_back(c, index(i, j, k + 1));
      }
  std::sort(p.neighbours.begin(), p.neighbours.end());
  // Each segment goes to the cells its bounding box overlaps in which it has positive length.
  const double tol = 1e-12 * box.diagonal();
  for (size_t s = 0; s < segs.size(); ++s) {
    const Vec3 a = segs.a(s), b = segs.b(s);
    int lo[3], hi[3];
    for (int ax = 0; ax < 3; ++ax) {
      auto cell_of = [&](double x) {
        return std::clamp(static_cast<int>(std::floor((x - box.lo[ax]) / e[ax] * n[ax])), 0, n[ax] - 1);
      };
      lo[ax] = cell_of(std::min(a[ax], b[ax]));
      hi[ax] = cell_of(std::max(a[ax], b[ax]));
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          double t0, t1;
          if (!clip_line_to_box(p.bounds[index(i, j, k)], a, b - a, t0, t1)) continue;
          if ((std::min(t1, 1.0) - std::max(t0, 0.0)) * length(b - a) <= tol) continue;
          for (uint32_t o : {segs.object_a[s], segs.object_b[s]})
            if (o != kNoObject) p.pvs[index(i, j, k)].push_back(o);
        }
  }
  for (auto& v : p.pvs) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
  return p;
}

double MergeHistory::cost_with(size_t cells) const {
  VC_CHECK(cells >= min_cells() && cells <= leaf_count);
  const size_t k = leaf_count - cells;
  return k == 0 ? initial_cost : cost_after[k - 1];
}

std::vector<int32_t> MergeHistory::cut_after(size_t k) const {
  VC_CHECK(k <= merges());
  const int32_t created = static_cast<int32_t>(leaf_count + k);  // nodes below this exist
  std::vector<int32_t> cut;
  for (int32_t n = 0; n < created; ++n)
    if (nodes[n].parent < 0 || nodes[n].parent >= created) cut.push_back(n);
  return cut;
}

std::vector<uint32_t> MergeHistory::leaves_under(int32_t n) const {
  std::vector<uint32_t> out;
  std::vector<int32_t> stack = {n};
  while (!stack.empty()) {
    const int32_t m = stack.back();
    stack.pop_back();
    if (nodes[m].child[0] < 0) {
      out.push_back(static_cast<uint32_t>(m));
    } else {
      stack.push_back(nodes[m].child[0]);
      stack.push_back(nodes[m].child[1]);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace viewcells
