// Merging, the merge history tree and extraction (view-cell-construction paper, 4.3 and 5.1).
#include <gtest/gtest.h>

#include "support/test_scenes.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <set>

#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/parallel.h"
#include "viewcells/merge/merge.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

SegmentSet sample(const Scene& scene, uint64_t samples, uint64_t seed = 1) {
  return test::sample_scene(scene, samples, seed);
}

struct Fixture {
  Scene scene;
  SegmentSet segs;
  Subdivision sub;
  CellPartition partition;
};

Fixture office(uint32_t cells, int size = 2, uint64_t samples = 30000) {
  Fixture f;
  f.scene = generate_scene({GeneratorKind::kOffice, 1, size});
  f.segs = sample(f.scene, samples);
  SubdivisionConfig config;
  config.max_cells = cells;
  config.show_progress = false;
  f.sub = subdivide(f.scene, f.segs, CostModel{}, config);
  f.partition = partition_from_subdivision(f.sub, leaf_pvs(f.sub, f.segs));
  return f;
}

MergeHistory merge(const Fixture& f, const CostModel& model = {}) {
  MergeConfig config;
  config.show_progress = false;
  return merge_cells(f.scene, f.partition, model, config);
}

/// The PVS of MHT node n: the union of its elementary cells' PVSs.
std::vector<uint32_t> union_pvs(const MergeHistory& h, const CellPartition& p, int32_t n) {
  std::vector<uint32_t> u;
  for (uint32_t leaf : h.leaves_under(n)) u.insert(u.end(), p.pvs[leaf].begin(), p.pvs[leaf].end());
  std::sort(u.begin(), u.end());
  u.erase(std::unique(u.begin(), u.end()), u.end());
  return u;
}

/// c(S) of a set of MHT nodes, recomputed from scratch (uniform density, c = 0).
double cost_from_scratch(const Scene& scene, const MergeHistory& h, const CellPartition& p,
                         const std::vector<int32_t>& cells) {
  const std::vector<double> r = per_object_costs(scene, CostModel{});
  double total_weight = 0;
  for (double w : p.weight) total_weight += w;
  double c = 0;
  for (int32_t n : cells) {
    double weight = 0, pvs = 0;
    for (uint32_t leaf : h.leaves_under(n)) weight += p.weight[leaf];
    for (uint32_t o : union_pvs(h, p, n)) pvs += r[o];
    c += weight / total_weight * pvs;
  }
  return c;
}

/// The cells tile the view space: their elementary cells are every leaf exactly once.
void expect_tiling(const MergeHistory& h, const CellPartition& p, const std::vector<int32_t>& cells) {
  std::vector<int> seen(h.leaf_count, 0);
  double volume = 0;
  for (int32_t n : cells) {
    for (uint32_t leaf : h.leaves_under(n)) ++seen[leaf];
    volume += h.nodes[n].volume;
  }
  for (uint32_t l = 0; l < h.leaf_count; ++l) ASSERT_EQ(seen[l], 1) << "leaf " << l;
  double total = 0;
  for (double v : p.volume) total += v;
  EXPECT_NEAR(volume / total, 1.0, 1e-9);
}

TEST(Merge, HistoryIsMonotoneAndMatchesRecomputedCosts) {
  const Fixture f = office(120);
  const MergeHistory h = merge(f);
  ASSERT_EQ(h.leaf_count, 120u);
  ASSERT_EQ(h.merges(), 119u) << "the BSP's neighbour graph is connected";
  EXPECT_EQ(h.min_cells(), 1u);
  EXPECT_NEAR(h.initial_cost, f.sub.cost(), 1e-9 * h.initial_cost) << "leaves cost what the subdivision said";
  double previous = h.initial_cost;
  for (size_t k = 0; k < h.merges(); ++k) {
    EXPECT_GE(h.cost_after[k], previous - 1e-12 * h.initial_cost) << "merge " << k;
    previous = h.cost_after[k];
  }
  for (size_t k : {0ul, 1ul, 30ul, 90ul, 118ul, 119ul}) {
    const std::vector<int32_t> cut = h.cut_after(k);
    ASSERT_EQ(cut.size(), h.leaf_count - k);
    expect_tiling(h, f.partition, cut);
    const double expected = cost_from_scratch(f.scene, h, f.partition, cut);
    EXPECT_NEAR(h.cost_with(cut.size()), expected, 1e-9 * expected) << k << " merges";
    for (int32_t n : cut) EXPECT_EQ(h.nodes[n].pvs_size, union_pvs(h, f.partition, n).size());
  }
  // The root sees everything any cell sees; its cost is the single cell's.
  const int32_t root = static_cast<int32_t>(h.nodes.size() - 1);
  EXPECT_EQ(h.nodes[root].parent, -1);
  EXPECT_NEAR(h.cost_after.back(), f.sub.initial_cost, 1e-9 * f.sub.initial_cost);
}

/// Every merge is the cheapest one among the neighbouring pairs of the cells at that point
/// (checked against all pairs, with neighbours recomputed from the elementary cells).
TEST(Merge, EachMergeIsTheCheapestNeighbouringPair) {
  const Fixture f = office(40, 1, 15000);
  const MergeHistory h = merge(f);
  const std::vector<double> r = per_object_costs(f.scene, CostModel{});
  double W = 0;
  for (double w : f.partition.weight) W += w;
  for (size_t k = 0; k < h.merges(); ++k) {
    const std::vector<int32_t> cut = h.cut_after(k);
    std::vector<int32_t> owner(h.leaf_count);
    for (int32_t n : cut)
      for (uint32_t leaf : h.leaves_under(n)) owner[leaf] = n;
    auto weight = [&](int32_t n) { return h.nodes[n].weight; };
    auto rcost = [&](const std::vector<uint32_t>& pvs) {
      double c = 0;
      for (uint32_t o : pvs) c += r[o];
      return c;
    };
    double best = INFINITY;
    for (const auto& [a, b] : f.partition.neighbours) {
      const int32_t x = owner[a], y = owner[b];
      if (x == y) continue;
      std::vector<uint32_t> u = union_pvs(h, f.partition, x);
      const std::vector<uint32_t> py = union_pvs(h, f.partition, y);
      u.insert(u.end(), py.begin(), py.end());
      std::sort(u.begin(), u.end());
      u.erase(std::unique(u.begin(), u.end()), u.end());
      const double delta = ((weight(x) + weight(y)) * rcost(u) - weight(x) * rcost(union_pvs(h, f.partition, x)) -
                            weight(y) * rcost(py)) / W;
      best = std::min(best, delta);
    }
    const double done = h.cost_after[k] - h.cost_with(h.leaf_count - k);
    EXPECT_NEAR(done, best, 1e-9 * h.initial_cost) << "merge " << k;
  }
}

/// Greedy merging done the slow way: every step evaluates every pair of neighbouring current
/// cells, r(x + y) summed over the united PVS in ascending order, and takes the least
/// (delta, x, y). Returns the merges as (child 0, child 1) in order. Without the pixel term.
std::vector<std::pair<int32_t, int32_t>> brute_force_merges(const Scene& scene, const CellPartition& p,
                                                             const CostModel& model) {
  const std::vector<double> r = per_object_costs(scene, model);
  auto rcost = [&](const std::vector<uint32_t>& pvs) {
    double c = 0;
    for (uint32_t o : pvs) c += r[o];
    return c;
  };
  const size_t L = p.size();
  std::vector<std::vector<uint32_t>> pvs(p.pvs.begin(), p.pvs.end());
  std::vector<double> weight(p.weight.begin(), p.weight.end()), cost;
  double W = 0;
  for (double w : weight) W += w;
  for (const auto& list : pvs) cost.push_back(rcost(list));
  std::vector<int32_t> owner(L);  // elementary cell -> current cell
  for (size_t i = 0; i < L; ++i) owner[i] = static_cast<int32_t>(i);
  std::vector<std::pair<int32_t, int32_t>> merges;
  for (;;) {
    double best = INFINITY;
    int32_t bx = -1, by = -1;
    for (const auto& [a, b] : p.neighbours) {
      const int32_t x = std::min(owner[a], owner[b]), y = std::max(owner[a], owner[b]);
      if (x == y) continue;
      std::vector<uint32_t> u;
      std::set_union(pvs[x].begin(), pvs[x].end(), pvs[y].begin(), pvs[y].end(), std::back_inserter(u));
      // r(x + y) = r(x) + r(y) - r(x n y), the shared objects summed in ascending order: what
      // the merge computes, bitwise.
      double common = 0;
      std::vector<uint32_t> both;
      std::set_intersection(pvs[x].begin(), pvs[x].end(), pvs[y].begin(), pvs[y].end(), std::back_inserter(both));
      for (uint32_t o : both) common += r[o];
      const double merged = cost[x] + cost[y] - common;
      const double delta = ((weight[x] + weight[y]) * merged - weight[x] * cost[x] - weight[y] * cost[y]) / W;
      if (delta < best || (delta == best && std::make_pair(x, y) < std::make_pair(bx, by))) {
        best = delta;
        bx = x;
        by = y;
      }
    }
    if (bx < 0) break;
    const int32_t z = static_cast<int32_t>(pvs.size());
    std::vector<uint32_t> u;
    std::set_union(pvs[bx].begin(), pvs[bx].end(), pvs[by].begin(), pvs[by].end(), std::back_inserter(u));
    pvs.push_back(u);
    weight.push_back(weight[bx] + weight[by]);
    cost.push_back(rcost(u));
    for (int32_t& o : owner)
      if (o == bx || o == by) o = z;
    merges.emplace_back(bx, by);
  }
  return merges;
}

/// The merge's queue, its pair costs (marks, whole-number sums) and its neighbour lists give
/// exactly the slow greedy's merges, ties included: on the office with the default model
/// (whole r(o)), with fractional r(o) (sums of doubles in order), and on a grid whose cells
/// outside the rooms have equal PVSs (many equal costs).
TEST(Merge, SameMergesAsBruteForceGreedy) {
  Fixture office_cells = office(50, 1, 15000);
  Fixture grid;
  grid.scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  grid.segs = sample(grid.scene, 15000);
  grid.partition = grid_partition(grid.segs, 6, 6, 2);
  size_t free_merges = 0;  // merges of equal PVSs (delta 0): many pairs tie at 0
  for (const Fixture* f : {&office_cells, &grid})
    for (const CostModel& model : {CostModel{}, CostModel{100.25, 0.7, 0}}) {
      MergeConfig config;
      config.show_progress = false;
      const MergeHistory h = merge_cells(f->scene, f->partition, model, config);
      const auto expected = brute_force_merges(f->scene, f->partition, model);
      ASSERT_EQ(h.merges(), expected.size());
      for (size_t k = 0; k < expected.size(); ++k) {
        const MergeNode& n = h.nodes[h.leaf_count + k];
        ASSERT_EQ(std::make_pair(n.child[0], n.child[1]), expected[k]) << "merge " << k << ", a = " << model.a;
      }
      for (size_t k = 1; k < h.merges(); ++k) free_merges += h.cost_after[k] == h.cost_after[k - 1];
    }
  EXPECT_GT(free_merges, 0u) << "the grid should give pairs of equal cost, so that the tie rule is exercised";
}

TEST(Merge, ExtractionByCountMemoryAndCostRatio) {
  const Fixture f = office(150);
  const MergeHistory h = merge(f);
  for (size_t n : {1ul, 2ul, 17ul, 100ul, 150ul}) {
    const ViewCellSet set = extract_by_count(h, n);
    ASSERT_EQ(set.cells.size(), n);
    expect_tiling(h, f.partition, set.cells);
    EXPECT_DOUBLE_EQ(set.cost, h.cost_with(n));
  }
  EXPECT_THROW(extract_by_count(h, 0), Error);
  EXPECT_THROW(extract_by_count(h, 151), Error);

  // Memory: never over the budget, and growing with it.
  const uint64_t finest = extract_by_count(h, 150).pvs_bytes, coarsest = extract_by_count(h, 1).pvs_bytes;
  size_t previous_cells = 0;
  for (uint64_t budget = coarsest; budget <= finest + 1000; budget += (finest - coarsest) / 13 + 1) {
    const ViewCellSet set = extract_by_memory(h, budget);
    EXPECT_LE(set.pvs_bytes, budget);
    uint64_t bytes = 0;
    for (int32_t c : set.cells) bytes += approx_pvs_bytes(static_cast<uint32_t>(union_pvs(h, f.partition, c).size()));
    EXPECT_EQ(bytes, set.pvs_bytes);
    EXPECT_GE(set.cells.size(), previous_cells);
    previous_cells = set.cells.size();
    expect_tiling(h, f.partition, set.cells);
  }
  EXPECT_EQ(previous_cells, 150u) << "a budget above the finest set's needs takes every cell";
  EXPECT_THROW(extract_by_memory(h, coarsest - 1), Error);

  // Cost ratio: within the ratio, and one cell fewer would not be.
  for (double ratio : {1.0, 1.05, 1.5, 3.0, 100.0}) {
    const ViewCellSet set = extract_by_cost_ratio(h, ratio);
    EXPECT_LE(set.cost, ratio * h.initial_cost);
    if (set.cells.size() > h.min_cells()) {
      EXPECT_GT(h.cost_with(set.cells.size() - 1), ratio * h.initial_cost);
    }
    expect_tiling(h, f.partition, set.cells);
  }
  EXPECT_EQ(extract_by_cost_ratio(h, 1e9).cells.size(), 1u);
  EXPECT_THROW(extract_by_cost_ratio(h, 0.5), Error);
}

TEST(Merge, MergesAGridPartition) {
  Fixture f;
  f.scene = generate_scene({GeneratorKind::kOffice, 1, 2});
  f.segs = sample(f.scene, 30000);
  f.partition = grid_partition(f.segs, 6, 5, 3);
  ASSERT_EQ(f.partition.size(), 90u);
  EXPECT_EQ(f.partition.neighbours.size(), 5u * 5 * 3 + 6 * 4 * 3 + 6 * 5 * 2);
  // A grid cell's PVS: the objects of the segments with length inside it (checked for one).
  const MergeHistory h = merge(f);
  EXPECT_EQ(h.merges(), 89u);
  for (size_t k : {0ul, 45ul, 89ul}) {
    const std::vector<int32_t> cut = h.cut_after(k);
    expect_tiling(h, f.partition, cut);
    const double expected = cost_from_scratch(f.scene, h, f.partition, cut);
    EXPECT_NEAR(h.cost_with(cut.size()), expected, 1e-9 * expected);
  }
  // The grid is coarse where AV-S adapts: at equal cell count AV-S + merging costs less.
  const Fixture ours = office(90);
  const MergeHistory ho = merge(ours);
  EXPECT_LT(ho.cost_with(30), h.cost_with(30));
}

TEST(Merge, IdenticalForOneAndTwoThreads) {
  const Fixture f = office(80);
  MergeHistory one;
  {
    ThreadLimit limit(1);
    one = merge(f);
  }
  const MergeHistory two = merge(f);
  ASSERT_EQ(one.nodes.size(), two.nodes.size());
  for (size_t n = 0; n < one.nodes.size(); ++n) {
    EXPECT_EQ(one.nodes[n].child[0], two.nodes[n].child[0]);
    EXPECT_EQ(one.nodes[n].child[1], two.nodes[n].child[1]);
  }
  EXPECT_EQ(one.cost_after, two.cost_after);
}

TEST(Merge, PixelTermMergesWithCellCosts) {
  const Fixture f = office(60);
  CostModel pixel{100, 1, 0.01};
  const MergeHistory h = merge(f, pixel);
  EXPECT_EQ(h.merges(), 59u);
  // A merged cell's cost is the model's for its bounds and the union of its PVS.
  const std::vector<double> base = per_object_costs(f.scene, pixel);
  for (size_t n = h.leaf_count; n < h.nodes.size(); n += 7) {
    const std::vector<Vec3> points = pixel_estimation_points(h.nodes[n].bounds);
    double c = 0;
    for (uint32_t o : union_pvs(h, f.partition, static_cast<int32_t>(n)))
      c += cell_object_cost(f.scene.objects[o], base[o], points, pixel);
    EXPECT_NEAR(h.nodes[n].pvs_cost, c, 1e-9 * c);
  }
  EXPECT_GT(h.cost_after.back(), h.initial_cost);
}

TEST(Merge, BadInput) {
  const Fixture f = office(10, 1, 5000);
  CellPartition p = f.partition;
  p.pvs[3] = {5, 2};
  EXPECT_THROW(merge_cells(f.scene, p, CostModel{}), Error);
  p = f.partition;
  p.neighbours.push_back({0, 99});
  EXPECT_THROW(merge_cells(f.scene, p, CostModel{}), Error);
  EXPECT_THROW(merge_cells(f.scene, CellPartition{}, CostModel{}), Error);
  EXPECT_THROW(grid_partition(f.segs, 0, 1, 1), Error);
}

}  // namespace
}  // namespace viewcells

namespace viewcells {
namespace {

/// The leaves under each node of a cut, as sets, for comparing cuts of different trees.
std::vector<std::vector<uint32_t>> cut_leaves(const MergeHistory& h, size_t cells) {
  std::vector<std::vector<uint32_t>> out;
  for (int32_t n : h.cut_after(h.leaf_count - cells)) out.push_back(h.leaves_under(n));
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::vector<uint32_t>> subdivision_cut_leaves(const Subdivision& s, size_t cells) {
  const std::vector<int32_t> leaves = s.leaves();
  std::vector<int32_t> index(s.nodes.size(), -1);
  for (size_t i = 0; i < leaves.size(); ++i) index[leaves[i]] = static_cast<int32_t>(i);
  std::vector<std::vector<uint32_t>> out;
  for (int32_t n : s.leaves_after(cells - 1)) {
    std::vector<uint32_t> under;
    std::vector<int32_t> stack = {n};
    while (!stack.empty()) {
      const int32_t m = stack.back();
      stack.pop_back();
      if (s.nodes[m].plane < 0) under.push_back(static_cast<uint32_t>(index[m]));
      else stack.insert(stack.end(), {s.nodes[m].child[0], s.nodes[m].child[1]});
    }
    std::sort(under.begin(), under.end());
    out.push_back(under);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Merge, PrefixReplaysTheSubdivisionsOwnCuts) {
  const Fixture f = office(90);
  MergeConfig config;
  config.show_progress = false;
  config.prefix = subdivision_prefix(f.sub, 1);
  ASSERT_EQ(config.prefix.size(), 89u);
  const MergeHistory h = merge_cells(f.scene, f.partition, CostModel{}, config);
  EXPECT_EQ(h.stats.evaluations, 0u) << "nothing left to choose greedily";
  for (size_t cells : {90ul, 60ul, 17ul, 5ul, 1ul}) {
    EXPECT_EQ(cut_leaves(h, cells), subdivision_cut_leaves(f.sub, cells)) << cells << " cells";
    // The subdivision's own cost at that count, from the same construction samples.
    const double expected = cells == 1 ? f.sub.initial_cost : f.sub.splits[cells - 2].cost_after;
    EXPECT_NEAR(h.cost_with(cells), expected, 1e-9 * expected) << cells << " cells";
  }
  // Part of the order, then greedy: the cuts down to the start are the subdivision's.
  config.prefix = subdivision_prefix(f.sub, 30);
  const MergeHistory g = merge_cells(f.scene, f.partition, CostModel{}, config);
  EXPECT_EQ(cut_leaves(g, 30), subdivision_cut_leaves(f.sub, 30));
  EXPECT_EQ(g.merges(), 89u);
  EXPECT_LE(g.cost_with(10), h.cost_with(10) * 1.5);
}

/// Greedy merging that stays inside the subdivision's cut at `cells` cells until there.
MergeConfig barrier_at(const Fixture& f, uint32_t cells) {
  MergeConfig config;
  config.show_progress = false;
  config.barrier_cells = cells;
  config.block = subdivision_blocks(f.sub, cells);
  return config;
}

TEST(Merge, BarrierKeepsGreedyMergesInsideTheSubdivisionsCut) {
  const Fixture f = office(90);
  const MergeConfig config = barrier_at(f, 12);
  const MergeHistory h = merge_cells(f.scene, f.partition, CostModel{}, config);
  // At the barrier the cut is exactly the subdivision's; above it every cell lies in a block.
  EXPECT_EQ(cut_leaves(h, 12), subdivision_cut_leaves(f.sub, 12));
  for (size_t cells : {80ul, 40ul, 20ul, 13ul})
    for (const std::vector<uint32_t>& cell : cut_leaves(h, cells))
      for (uint32_t leaf : cell) EXPECT_EQ(config.block[leaf], config.block[cell.front()]) << cells << " cells";
  EXPECT_EQ(h.merges(), 89u) << "greedy merging goes on below the barrier";
}

TEST(Merge, HistoriesJoinWhereTheirCutsAgree) {
  const Fixture f = office(90);
  MergeConfig config = barrier_at(f, 12);
  const MergeHistory upper = merge_cells(f.scene, f.partition, CostModel{}, config);  // AV-S's cut at 12
  config.barrier_cells = 0;
  config.block.clear();
  config.prefix = subdivision_prefix(f.sub, 6);
  const MergeHistory lower = merge_cells(f.scene, f.partition, CostModel{}, config);  // AV-S's cuts 90..6
  ASSERT_EQ(cut_leaves(upper, 12), cut_leaves(lower, 12));
  // upper's merges down to 12 cells, then lower's from there.
  std::vector<std::pair<int32_t, int32_t>> joined = merges_by_least_leaf(upper);
  const std::vector<std::pair<int32_t, int32_t>> rest = merges_by_least_leaf(lower);
  joined.resize(90 - 12);
  joined.insert(joined.end(), rest.begin() + (90 - 12), rest.end());
  config.prefix = least_leaf_merges_as_prefix(joined, 90);
  const MergeHistory h = merge_cells(f.scene, f.partition, CostModel{}, config);
  EXPECT_EQ(h.stats.evaluations, 0u) << "every merge was given";
  for (size_t cells = 90; cells >= 1; --cells) {
    const MergeHistory& from = cells > 12 ? upper : lower;
    EXPECT_EQ(cut_leaves(h, cells), cut_leaves(from, cells)) << cells << " cells";
    EXPECT_NEAR(h.cost_with(cells), from.cost_with(cells), 1e-9 * from.cost_with(cells)) << cells << " cells";
  }
  // A history replays itself, node for node.
  config.prefix = least_leaf_merges_as_prefix(merges_by_least_leaf(upper), 90);
  const MergeHistory again = merge_cells(f.scene, f.partition, CostModel{}, config);
  for (size_t k = 90; k < upper.nodes.size(); ++k)
    EXPECT_EQ(again.nodes[k].child[0], upper.nodes[k].child[0]) << k;
  // Names that are not leaves are refused.
  EXPECT_THROW(least_leaf_merges_as_prefix({{0, 90}}, 90), Error);
  EXPECT_THROW(least_leaf_merges_as_prefix({{3, 3}}, 90), Error);
}

/// Per block label, c(S) summed as refine_blocks counts it: weight x r(union of its cells' PVSs).
double blocks_cost(const Fixture& f, const std::vector<int32_t>& block) {
  const std::vector<double> r = per_object_costs(f.scene, CostModel{});
  std::map<int32_t, std::pair<double, std::set<uint32_t>>> by;
  for (size_t c = 0; c < block.size(); ++c) {
    by[block[c]].first += f.partition.weight[c];
    by[block[c]].second.insert(f.partition.pvs[c].begin(), f.partition.pvs[c].end());
  }
  double total = 0;
  for (const auto& [b, wp] : by) {
    double rp = 0;
    for (uint32_t o : wp.second) rp += r[o];
    total += wp.first * rp;
  }
  return total;
}

/// Whether every block's cells are connected through the partition's neighbours.
bool blocks_connected(const Fixture& f, const std::vector<int32_t>& block) {
  std::vector<std::vector<uint32_t>> next(block.size());
  for (const auto& [a, b] : f.partition.neighbours)
    if (block[a] == block[b]) {
      next[a].push_back(b);
      next[b].push_back(a);
    }
  std::vector<bool> seen(block.size(), false);
  std::set<int32_t> started;
  for (uint32_t c = 0; c < block.size(); ++c) {
    if (seen[c]) continue;
    if (!started.insert(block[c]).second) return false;  // a second piece of a block
    std::vector<uint32_t> stack{c};
    seen[c] = true;
    while (!stack.empty()) {
      const uint32_t x = stack.back();
      stack.pop_back();
      for (uint32_t y : next[x])
        if (!seen[y]) {
          seen[y] = true;
          stack.push_back(y);
        }
    }
  }
  return true;
}

TEST(Merge, RefinedBlocksCostLessStayConnectedAndKeepUnitsWhole) {
  const Fixture f = office(200);
  const std::vector<int32_t> unit = subdivision_blocks(f.sub, 100);
  uint64_t moves = 0;
  for (size_t cells : {8ul, 12ul, 16ul, 24ul}) {
    SCOPED_TRACE(std::to_string(cells) + " blocks");
    const std::vector<int32_t> block = subdivision_blocks(f.sub, cells);
    RefineStats st;
    const std::vector<int32_t> refined = refine_blocks(f.scene, f.partition, CostModel{}, unit, block, 50, &st);
    moves += st.moves;
    EXPECT_LT(st.passes, 50u) << "passes end when no unit moves";
    EXPECT_NEAR(st.cost_before, blocks_cost(f, block), 1e-9 * st.cost_before);
    EXPECT_NEAR(st.cost_after, blocks_cost(f, refined), 1e-9 * st.cost_after);
    if (st.moves) {
      EXPECT_LT(st.cost_after, st.cost_before);
    }
    EXPECT_TRUE(blocks_connected(f, block));
    EXPECT_TRUE(blocks_connected(f, refined));
    EXPECT_EQ(std::set<int32_t>(refined.begin(), refined.end()), std::set<int32_t>(block.begin(), block.end()))
        << "the same labels, none emptied";
    std::map<int32_t, int32_t> unit_block;
    for (size_t c = 0; c < unit.size(); ++c) {
      const auto [it, fresh] = unit_block.emplace(unit[c], refined[c]);
      EXPECT_EQ(it->second, refined[c]) << "unit " << unit[c] << " split";
    }
    EXPECT_EQ(refine_blocks(f.scene, f.partition, CostModel{}, unit, block), refined) << "deterministic";
    // A local optimum: no unit lowers the cost by moving to a neighbouring block that keeps
    // its own block connected.
    const double tolerance = 1e-9 * st.cost_after;
    for (const auto& [u, b] : unit_block) {
      std::set<int32_t> targets;
      for (const auto& [x, y] : f.partition.neighbours)
        for (auto [in, out] : {std::pair{x, y}, std::pair{y, x}})
          if (unit[in] == u && refined[out] != b) targets.insert(refined[out]);
      for (int32_t t : targets) {
        std::vector<int32_t> moved = refined;
        for (size_t c = 0; c < unit.size(); ++c)
          if (unit[c] == u) moved[c] = t;
        if (std::count(moved.begin(), moved.end(), b) == 0 || !blocks_connected(f, moved)) continue;
        EXPECT_GE(blocks_cost(f, moved), st.cost_after - tolerance) << "unit " << u << " to block " << t;
      }
    }
    // Merging within the refined blocks reaches them exactly at the barrier.
    MergeConfig config;
    config.show_progress = false;
    config.barrier_cells = static_cast<uint32_t>(cells);
    config.block = refined;
    const MergeHistory h = merge_cells(f.scene, f.partition, CostModel{}, config);
    std::set<std::vector<uint32_t>> want;
    for (int32_t b : std::set<int32_t>(refined.begin(), refined.end())) {
      std::vector<uint32_t> members;
      for (uint32_t c = 0; c < refined.size(); ++c)
        if (refined[c] == b) members.push_back(c);
      want.insert(members);
    }
    const std::vector<std::vector<uint32_t>> got = cut_leaves(h, cells);
    EXPECT_EQ(std::set<std::vector<uint32_t>>(got.begin(), got.end()), want);
  }
  EXPECT_GT(moves, 0u) << "the subdivision's cuts at 8 to 24 cells are all local optima of c(S)?";
  // A unit across two blocks, or the pixel term, is refused.
  const std::vector<int32_t> block = subdivision_blocks(f.sub, 12);
  EXPECT_THROW(refine_blocks(f.scene, f.partition, CostModel{}, block, unit), Error);
  CostModel pixels;
  pixels.c = 1;
  EXPECT_THROW(refine_blocks(f.scene, f.partition, pixels, unit, block), Error);
}

/// Whether two histories are the same, node for node and cost for cost (bitwise).
void expect_same_history(const MergeHistory& a, const MergeHistory& b, const std::string& what) {
  ASSERT_EQ(a.nodes.size(), b.nodes.size()) << what;
  for (size_t k = 0; k < a.nodes.size(); ++k) {
    EXPECT_EQ(a.nodes[k].child[0], b.nodes[k].child[0]) << what << ", node " << k;
    EXPECT_EQ(a.nodes[k].child[1], b.nodes[k].child[1]) << what << ", node " << k;
    EXPECT_EQ(a.nodes[k].parent, b.nodes[k].parent) << what << ", node " << k;
    EXPECT_EQ(a.nodes[k].pvs_cost, b.nodes[k].pvs_cost) << what << ", node " << k;
    EXPECT_EQ(a.nodes[k].weight, b.nodes[k].weight) << what << ", node " << k;
  }
  EXPECT_EQ(a.cost_after, b.cost_after) << what;
  EXPECT_EQ(a.initial_cost, b.initial_cost) << what;
  EXPECT_EQ(a.stats.evaluations, b.stats.evaluations) << what;
  EXPECT_EQ(a.stats.stale, b.stats.stale) << what;
}

TEST(Merge, SharedPrefixGivesEachConfigItsOwnHistory) {
  const Fixture f = office(90);
  for (const bool pixel : {false, true}) {  // narrow and wide ids
    const CostModel model = pixel ? CostModel{100, 1, 0.01} : CostModel{};
    std::vector<MergeConfig> configs;
    auto add = [&](size_t start, uint32_t barrier, uint32_t min_cells) {
      MergeConfig c;
      c.show_progress = false;
      c.prefix = subdivision_prefix(f.sub, start);
      c.barrier_cells = barrier;
      if (barrier) c.block = subdivision_blocks(f.sub, barrier);
      c.min_cells = min_cells;
      configs.push_back(std::move(c));
    };
    add(30, 0, 1);
    add(90, 0, 1);   // no prefix
    add(30, 8, 1);   // the same prefix, a barrier below it
    add(60, 15, 1);
    add(12, 0, 20);  // stops inside its prefix, at 20 cells
    add(6, 0, 1);
    add(1, 0, 1);    // the whole prefix: nothing left to choose
    add(60, 0, 3);
    std::vector<MergeHistory> shared(configs.size());
    std::vector<int> calls(configs.size(), 0);
    merge_cells_sharing_prefix(f.scene, f.partition, model, configs, [&](size_t i, MergeHistory h) {
      ++calls[i];  // each config's own slot: no two calls write the same one
      shared[i] = std::move(h);
    });
    for (size_t i = 0; i < configs.size(); ++i) {
      const std::string what = std::string(pixel ? "pixel term, " : "") + "config " + std::to_string(i);
      EXPECT_EQ(calls[i], 1) << what;
      expect_same_history(shared[i], merge_cells(f.scene, f.partition, model, configs[i]), what);
    }
    EXPECT_EQ(shared[4].min_cells(), 20u);
    EXPECT_EQ(shared[6].stats.evaluations, 0u);
  }
  // Prefixes that are not the first merges of the longest are refused; so is a bad config.
  MergeConfig a, b;
  a.show_progress = b.show_progress = false;
  a.prefix = subdivision_prefix(f.sub, 30);
  b.prefix = {{1, 2}};
  auto ignore = [](size_t, MergeHistory) {};
  EXPECT_THROW(merge_cells_sharing_prefix(f.scene, f.partition, CostModel{}, {a, b}, ignore), Error);
  b.prefix = subdivision_prefix(f.sub, 40);
  b.block = {0, 1};
  b.barrier_cells = 2;
  EXPECT_THROW(merge_cells_sharing_prefix(f.scene, f.partition, CostModel{}, {a, b}, ignore), Error);
  merge_cells_sharing_prefix(f.scene, f.partition, CostModel{}, {}, ignore);  // nothing to do
}

TEST(Merge, PrefixAndBlocksAreChecked) {
  const Fixture f = office(20);
  MergeConfig config;
  config.show_progress = false;
  config.prefix = {{0, 0}};
  EXPECT_THROW(merge_cells(f.scene, f.partition, CostModel{}, config), Error);
  config.prefix = {{0, 1}, {0, 2}};  // 0 has merged already
  EXPECT_THROW(merge_cells(f.scene, f.partition, CostModel{}, config), Error);
  config.prefix = {{0, 99}};
  EXPECT_THROW(merge_cells(f.scene, f.partition, CostModel{}, config), Error);
  config.prefix.clear();
  config.block = {0, 1};
  config.barrier_cells = 2;
  EXPECT_THROW(merge_cells(f.scene, f.partition, CostModel{}, config), Error);
}

}  // namespace
}  // namespace viewcells
