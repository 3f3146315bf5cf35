// Boundary refinement of blocks of a partition (merge/merge.h: refine_blocks).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "viewcells/core/error.h"
#include "viewcells/merge/merge.h"

namespace viewcells {

std::vector<int32_t> refine_blocks(const Scene& scene, const CellPartition& partition, const CostModel& model,
                                   const std::vector<int32_t>& unit, const std::vector<int32_t>& block,
                                   uint32_t max_passes, RefineStats* stats) {
  const size_t n = partition.size();
  if (unit.size() != n) throw Error("refine_blocks: one unit per partition cell");
  if (model.pixel_term()) throw Error("refine_blocks: the pixel term is not supported");
  const std::vector<double> r = per_object_costs(scene, model);
  // Units: dense ids, their weights, PVSs (unions of their cells') and neighbours.
  std::vector<int32_t> id(n);
  std::vector<int32_t> names;  // unit label -> dense id
  {
    std::vector<int32_t> sorted = unit;
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    names = std::move(sorted);
    for (size_t c = 0; c < n; ++c)
      id[c] = static_cast<int32_t>(std::lower_bound(names.begin(), names.end(), unit[c]) - names.begin());
  }
  const size_t u = names.size();
  std::vector<double> w(u, 0.0);
  // Each unit's PVS, the union of its cells': cells grouped by unit, objects deduplicated by
  // a stamp per object (linear in the cells' entries; only the unions are sorted).
  std::vector<uint32_t> first(u + 1, 0), cells_by_unit(n);
  for (size_t c = 0; c < n; ++c) ++first[id[c] + 1];
  for (size_t x = 0; x < u; ++x) first[x + 1] += first[x];
  {
    std::vector<uint32_t> at(first.begin(), first.end() - 1);
    for (size_t c = 0; c < n; ++c) cells_by_unit[at[id[c]]++] = static_cast<uint32_t>(c);
  }
  std::vector<std::vector<uint32_t>> pvs(u);
  std::vector<uint32_t> stamp(r.size(), UINT32_MAX);
  for (size_t x = 0; x < u; ++x) {
    auto& l = pvs[x];
    for (uint32_t i = first[x]; i < first[x + 1]; ++i) {
      const uint32_t c = cells_by_unit[i];
      w[x] += partition.weight[c];
      for (uint32_t o : partition.pvs[c])
        if (stamp[o] != x) {
          stamp[o] = static_cast<uint32_t>(x);
          l.push_back(o);
        }
    }
    std::sort(l.begin(), l.end());
  }
  std::vector<std::vector<int32_t>> next(u);
  for (const auto& [a, b] : partition.neighbours) {
    const int32_t x = id[a], y = id[b];
    if (x != y) {
      next[x].push_back(y);
      next[y].push_back(x);
    }
  }
  for (auto& l : next) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
  }
  // Blocks: each unit's (every cell of a unit must share it), dense ids.
  std::vector<int32_t> of(u, -1);
  for (size_t c = 0; c < n; ++c) {
    if (of[id[c]] >= 0 && of[id[c]] != block[c]) throw Error("refine_blocks: a unit lies in two blocks");
    of[id[c]] = block[c];
  }
  std::vector<int32_t> bnames = of;
  std::sort(bnames.begin(), bnames.end());
  bnames.erase(std::unique(bnames.begin(), bnames.end()), bnames.end());
  const size_t k = bnames.size();
  for (int32_t& b : of) b = static_cast<int32_t>(std::lower_bound(bnames.begin(), bnames.end(), b) - bnames.begin());
  const size_t objects = r.size();
  std::vector<uint32_t> count(k * objects, 0);
  std::vector<double> W(k, 0.0), R(k, 0.0);
  std::vector<uint32_t> size(k, 0);
  for (size_t x = 0; x < u; ++x) {
    const size_t b = static_cast<size_t>(of[x]);
    W[b] += w[x];
    ++size[b];
    for (uint32_t o : pvs[x])
      if (count[b * objects + o]++ == 0) R[b] += r[o];
  }
  double total = 0;
  for (size_t b = 0; b < k; ++b) total += W[b] * R[b];
  const double initial = total;
  // Whether block b stays connected without unit x (b has more than one unit).
  std::vector<uint32_t> seen(u, 0);
  uint32_t epoch = 0;
  std::vector<int32_t> stack;
  auto connected_without = [&](int32_t x, int32_t b) {
    ++epoch;
    int32_t start = -1;
    for (int32_t y : next[x])
      if (of[y] == b) {
        start = y;
        break;
      }
    if (start < 0) return false;
    seen[x] = epoch;
    seen[start] = epoch;
    stack.assign(1, start);
    uint32_t reached = 1;
    while (!stack.empty()) {
      const int32_t y = stack.back();
      stack.pop_back();
      for (int32_t z : next[y])
        if (of[z] == b && seen[z] != epoch) {
          seen[z] = epoch;
          ++reached;
          stack.push_back(z);
        }
    }
    return reached == size[b] - 1;
  };
  uint32_t passes = 0;
  uint64_t moves = 0;
  std::vector<int32_t> targets;
  for (; passes < max_passes; ++passes) {
    uint64_t moved = 0;
    for (size_t xi = 0; xi < u; ++xi) {
      const auto x = static_cast<int32_t>(xi);
      const int32_t a = of[x];
      if (size[a] <= 1) continue;
      targets.clear();
      for (int32_t y : next[x])
        if (of[y] != a) targets.push_back(of[y]);
      if (targets.empty()) continue;
      std::sort(targets.begin(), targets.end());
      targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
      double drop = 0;
      for (uint32_t o : pvs[x])
        if (count[static_cast<size_t>(a) * objects + o] == 1) drop += r[o];
      const double after_a = (W[a] - w[x]) * (R[a] - drop), before_a = W[a] * R[a];
      double best = 0;
      int32_t to = -1;
      for (int32_t b : targets) {
        double add = 0;
        for (uint32_t o : pvs[x])
          if (count[static_cast<size_t>(b) * objects + o] == 0) add += r[o];
        const double gain = before_a + W[b] * R[b] - after_a - (W[b] + w[x]) * (R[b] + add);
        if (gain > best) {
          best = gain;
          to = b;
        }
      }
      // Gains below rounding of the total are not moves (no cycling on ties).
      if (to < 0 || !(best > 1e-12 * total) || !connected_without(x, a)) continue;
      for (uint32_t o : pvs[x]) {
        if (--count[static_cast<size_t>(a) * objects + o] == 0) R[a] -= r[o];
        if (count[static_cast<size_t>(to) * objects + o]++ == 0) R[to] += r[o];
      }
      W[a] -= w[x];
      W[to] += w[x];
      --size[a];
      ++size[to];
      of[x] = to;
      total -= best;
      ++moved;
    }
    moves += moved;
    if (!moved) break;
  }
  if (stats) {
    stats->passes = passes;
    stats->moves = moves;
    stats->cost_before = initial;
    stats->cost_after = total;
  }
  std::vector<int32_t> out(n);
  for (size_t c = 0; c < n; ++c) out[c] = bnames[static_cast<size_t>(of[id[c]])];
  return out;
}

}  // namespace viewcells
