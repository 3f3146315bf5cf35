// AGVS paper 3.1 and 4.1: the view cells a segment pierces, and the global PVS it contributes to (a bit
// per cell and object).
#include "viewcells/agvs/agvs.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>

#include "viewcells/agvs/penumbra.h"
#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"
#include "viewcells/io/binary_file.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells {

// ------------------------------------------------------------------------------ cells, PVS

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
}

int32_t CellLocator::cell_at(const Vec3& p) const {
  const int32_t leaf = bsp_.locate(p);
  return leaf < 0 ? -1 : leaf_cell_[leaf];
}

void CellLocator::cells_of_segment(const Vec3& a, const Vec3& b, std::vector<int32_t>& out,
                                   std::vector<std::tuple<int32_t, double, double>>& stack,
                                   std::vector<int32_t>& leaves) const {
  leaves.clear();
  bsp_.leaves_of_segment(a, b, leaves, stack);
  out.clear();
  for (int32_t l : leaves) out.push_back(leaf_cell_[l]);
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

GlobalPvs::GlobalPvs(uint32_t cells, uint32_t objects)
    : cells_(cells), objects_(objects), words_((objects + 63) / 64), bits_(size_t(cells) * words_, 0), sizes_(cells, 0) {}

GlobalPvs GlobalPvs::from_lists(uint32_t objects, const std::vector<std::vector<uint32_t>>& lists) {
  GlobalPvs p(static_cast<uint32_t>(lists.size()), objects);
  for (uint32_t c = 0; c < lists.size(); ++c)
    for (uint32_t o : lists[c]) p.insert(c, o);
  return p;
}

bool GlobalPvs::insert(uint32_t cell, uint32_t object) {
  uint64_t& w = bits_[size_t(cell) * words_ + object / 64];
  const uint64_t bit = uint64_t{1} << (object % 64);
  if (w & bit) return false;
  w |= bit;
  ++sizes_[cell];
  ++entries_;
  return true;
}

bool GlobalPvs::erase(uint32_t cell, uint32_t object) {
  uint64_t& w = bits_[size_t(cell) * words_ + object / 64];
  const uint64_t bit = uint64_t{1} << (object % 64);
  if (!(w & bit)) return false;
  w &= ~bit;
  --sizes_[cell];
  --entries_;
  return true;
}

uint64_t GlobalPvs::common_entries(const GlobalPvs& other) const {
  if (other.cells_ != cells_ || other.objects_ != objects_) throw Error("PVS tables of different shapes");
  uint64_t n = 0;
  for (size_t w = 0; w < bits_.size(); ++w) n += static_cast<uint64_t>(__builtin_popcountll(bits_[w] & other.bits_[w]));
  return n;
}

std::vector<uint32_t> GlobalPvs::list(uint32_t cell) const {
  std::vector<uint32_t> out;
  out.reserve(sizes_[cell]);
  for (size_t w = 0; w < words_; ++w)
    for (uint64_t bits = bits_[size_t(cell) * words_ + w]; bits; bits &= bits - 1)
      out.push_back(static_cast<uint32_t>(w * 64 + __builtin_ctzll(bits)));
  return out;
}

uint32_t contribute(GlobalPvs& pvs, const std::vector<int32_t>& cells, uint32_t object_a, uint32_t object_b,
                    bool contributed[2], int32_t origin_cell, bool at_origin[2]) {
  const uint32_t objs[2] = {object_a, object_b};
  uint32_t gain = 0;
  for (int32_t cell : cells)
    for (int e = 0; e < 2; ++e) {
      if (objs[e] == kNoObject || (e == 1 && objs[1] == objs[0])) continue;
      if (!pvs.insert(static_cast<uint32_t>(cell), objs[e])) continue;
      ++gain;
      if (contributed) contributed[e] = true;
      if (at_origin && cell == origin_cell) at_origin[e] = true;
    }
  // Both ends see the same object: both rays were wrong pixels before.
  if (at_origin && objs[0] == objs[1] && objs[0] != kNoObject) at_origin[1] = at_origin[0];
  return gain;
}

}  // namespace viewcells
