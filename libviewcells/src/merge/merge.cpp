// View space merging (view-cell-construction paper, section 4.3) and extraction (section 5.1).
//
// The neighbour graph is a sorted neighbour list per merge-history node id: merging x and y
// adds node z (the largest id so far, so appending it keeps every list sorted) with the union
// of their neighbours and clears x and y. The queue holds (delta, x, y); an entry whose x or y
// has merged since is stale and skipped when popped, so the queue is never rescanned. delta
// needs only the objects the two PVSs share when the object costs do not depend on the cell
// (c = 0): r(x + y) = r(x) + r(y) - r(x n y). One cell's objects are marked with their r(o) in
// an array over the objects, and each partner's list sums its marks in its own (ascending)
// order, adding 0 for the objects not shared: the same additions in the same order as walking
// the two lists together, without the walk's unpredictable branches.
#include "viewcells/merge/merge.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <queue>

#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"

namespace viewcells {

CellPartition partition_from_subdivision(const Subdivision& s, const std::vector<std::vector<uint32_t>>& leaf_pvs) {
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
    p.pvs.push_back(leaf_pvs[n]);
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

namespace {

struct Entry {
  double delta;
  int32_t x, y;  // x < y
};
struct Later {  // min-heap on delta; ties: smaller ids first
  bool operator()(const Entry& p, const Entry& q) const {
    if (p.delta != q.delta) return p.delta > q.delta;
    return p.x != q.x ? p.x > q.x : p.y > q.y;
  }
};

class Merger {
 public:
  Merger(const Scene& scene, const CellPartition& p, const CostModel& model)
      : scene_(scene), p_(p), model_(model), r_(per_object_costs(scene, model)), whole_costs_(whole_and_small(r_)),
        marks_([n = scene.objects.size()] { return std::vector<double>(n, 0.0); }) {}

  MergeHistory run(const MergeConfig& config) {
    const auto start = std::chrono::steady_clock::now();
    const size_t L = p_.size();
    MergeHistory h;
    h.leaf_count = static_cast<uint32_t>(L);
    h.nodes.resize(L);
    pvs_.resize(2 * L);
    adjacent_.assign(2 * L, {});
    for (size_t i = 0; i < L; ++i) {
      MergeNode& n = h.nodes[i];
      n.weight = p_.weight[i];
      n.volume = p_.volume[i];
      n.bounds = p_.bounds[i];
      pvs_[i] = p_.pvs[i];
      n.pvs_cost = pvs_cost(pvs_[i], n.bounds);
      n.pvs_size = static_cast<uint32_t>(pvs_[i].size());
      h.total_weight += n.weight;
    }
    if (!(h.total_weight > 0)) throw Error("the cells to merge have no weight");
    W_ = h.total_weight;
    for (size_t i = 0; i < L; ++i) h.initial_cost += h.nodes[i].weight / W_ * h.nodes[i].pvs_cost;
    for (const auto& [a, b] : p_.neighbours)
      if (a != b) {
        adjacent_[a].push_back(static_cast<int32_t>(b));
        adjacent_[b].push_back(static_cast<int32_t>(a));
      }
    for (std::vector<int32_t>& list : adjacent_) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }

    const size_t target = std::max<size_t>(1, config.min_cells);
    alive_ = L;
    cost_ = h.initial_cost;
    Progress progress("merging", L > target ? L - target : 0);
    std::vector<int32_t> around;
    for (const auto& [x, y] : config.prefix) {
      if (alive_ <= target) break;
      check_prefix_pair(h, x, y);
      merge(h, x, y, around);
      if (config.show_progress) progress.advance(1);
    }
    if (!config.block.empty()) {
      if (config.block.size() != L) throw Error("the merge blocks do not match the partition");
      block_.assign(2 * L, -1);
      for (size_t i = 0; i < L; ++i) block_[i] = config.block[i];
      for (size_t k = L; k < h.nodes.size(); ++k) block_[k] = block_[h.nodes[k].child[0]];
    }
    constrained_ = !config.block.empty() && alive_ > config.barrier_cells;
    std::priority_queue<Entry, std::vector<Entry>, Later> queue(Later{}, all_pairs(h));
    std::vector<Entry> fresh;
    while (alive_ > target) {
      if (queue.empty()) {
        if (!constrained_) break;
        constrained_ = false;  // blocks that cannot merge further: the barrier is lifted
        queue = decltype(queue)(Later{}, all_pairs(h));
        continue;
      }
      const Entry e = queue.top();
      queue.pop();
      if (h.nodes[e.x].parent >= 0 || h.nodes[e.y].parent >= 0) {
        ++h.stats.stale;
        continue;
      }
      const int32_t z = merge(h, e.x, e.y, around);
      if (constrained_) block_[z] = block_[e.x];
      if (config.show_progress) progress.advance(1);
      if (constrained_ && alive_ <= config.barrier_cells) {
        constrained_ = false;  // at the barrier: every neighbouring pair from now on
        queue = decltype(queue)(Later{}, all_pairs(h));
        continue;
      }
      fresh.clear();
      for (int32_t n : around)
        if (allowed(n, z)) fresh.push_back({0.0, n, z});
      evaluate(h, fresh, &Entry::y);
      for (const Entry& f : fresh) queue.push(f);
    }
    if (config.show_progress) progress.finish();
    h.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return h;
  }

 private:
  bool allowed(int32_t x, int32_t y) const { return !constrained_ || block_[x] == block_[y]; }

  /// Every allowed neighbouring pair of the current cells, evaluated.
  std::vector<Entry> all_pairs(MergeHistory& h) {
    std::vector<Entry> entries;
    for (size_t v = 0; v < h.nodes.size(); ++v)
      for (int32_t w : adjacent_[v])
        if (static_cast<int32_t>(v) < w && allowed(static_cast<int32_t>(v), w))
          entries.push_back({0.0, static_cast<int32_t>(v), w});
    evaluate(h, entries, &Entry::x);
    return entries;
  }

  void check_prefix_pair(const MergeHistory& h, int32_t x, int32_t y) const {
    const int32_t n = static_cast<int32_t>(h.nodes.size());
    if (x < 0 || y < 0 || x >= n || y >= n || x == y || h.nodes[x].parent >= 0 || h.nodes[y].parent >= 0)
      throw Error("a prefix merge names cells that are not current cells (" + std::to_string(x) + ", " +
                  std::to_string(y) + ")");
  }

  /// Merges current cells x and y into a new node z; `around` gets z's neighbours.
  int32_t merge(MergeHistory& h, int32_t x, int32_t y, std::vector<int32_t>& around) {
    const int32_t z = static_cast<int32_t>(h.nodes.size());
    MergeNode node;
    node.child[0] = x;
    node.child[1] = y;
    node.weight = h.nodes[x].weight + h.nodes[y].weight;
    node.volume = h.nodes[x].volume + h.nodes[y].volume;
    node.bounds = h.nodes[x].bounds;
    node.bounds.extend(h.nodes[y].bounds);
    pvs_[z] = unite_sorted(pvs_[x], pvs_[y]);
    node.pvs_cost = pvs_cost(pvs_[z], node.bounds);
    node.pvs_size = static_cast<uint32_t>(pvs_[z].size());
    // The recorded cost uses the merged cell's actual r(PVS), not the queued estimate.
    cost_ += (node.weight * node.pvs_cost - h.nodes[x].weight * h.nodes[x].pvs_cost -
              h.nodes[y].weight * h.nodes[y].pvs_cost) / W_;
    h.nodes.push_back(node);
    h.nodes[x].parent = z;
    h.nodes[y].parent = z;
    h.cost_after.push_back(cost_);
    --alive_;
    // z inherits the neighbours of x and y (both lists sorted, so their union is too).
    around.clear();
    std::set_union(adjacent_[x].begin(), adjacent_[x].end(), adjacent_[y].begin(), adjacent_[y].end(),
                   std::back_inserter(around));
    around.erase(std::remove_if(around.begin(), around.end(), [&](int32_t n) { return n == x || n == y; }),
                 around.end());
    for (int32_t n : around) {
      std::vector<int32_t>& list = adjacent_[n];
      list.erase(std::remove_if(list.begin(), list.end(), [&](int32_t m) { return m == x || m == y; }), list.end());
      list.push_back(z);  // z is the largest id so far: the list stays sorted
    }
    adjacent_[z] = around;
    adjacent_[x] = {};
    adjacent_[y] = {};
    pvs_[x] = {};
    pvs_[y] = {};
    return z;
  }

  double pvs_cost(const std::vector<uint32_t>& pvs, const Box3& bounds) const {
    return viewcells::pvs_cost(scene_, r_, model_, pvs, bounds);
  }

  /// delta(x, y) for every entry. Without the pixel term, consecutive entries that share their
  /// `shared` side (x or y) mark its objects once and sum the other side's marks.
  void evaluate(MergeHistory& h, std::vector<Entry>& entries, int32_t Entry::*shared) {
    h.stats.evaluations += entries.size();
    size_t work = 0;  // list entries read: small sets run without tasks
    for (const Entry& e : entries) work += pvs_[e.x].size() + pvs_[e.y].size();
    const size_t grain = work > (size_t{1} << 15) ? std::max<size_t>(1, entries.size() / 64) : entries.size() + 1;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, entries.size(), grain), [&](const tbb::blocked_range<size_t>& r) {
      if (model_.pixel_term()) {
        for (size_t i = r.begin(); i < r.end(); ++i) entries[i].delta = delta_united(h, entries[i].x, entries[i].y);
        return;
      }
      std::vector<double>& marks = marks_.local();
      int32_t marked = -1;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        Entry& e = entries[i];
        const int32_t s = e.*shared, other = s == e.x ? e.y : e.x;
        if (s != marked) {
          if (marked >= 0) set_marks(marks, marked, false);
          set_marks(marks, s, true);
          marked = s;
        }
        const double common = shared_cost(marks, pvs_[other]);
        const MergeNode &nx = h.nodes[e.x], &ny = h.nodes[e.y];
        e.delta = merged_delta(nx, ny, nx.pvs_cost + ny.pvs_cost - common);
      }
      if (marked >= 0) set_marks(marks, marked, false);
    });
  }

  /// r(x n y): the marks of x summed over y's objects. In ascending order, one addition after
  /// the other; or, when every r(o) is a whole number and their total is below 2^53 (the default
  /// model: max(a, b t_o) with whole a and b), in four running sums, which is then exact and so
  /// bitwise the same, without waiting on each addition.
  double shared_cost(const std::vector<double>& marks, const std::vector<uint32_t>& list) const {
    const size_t n = list.size();
    const uint32_t* o = list.data();
    const double* m = marks.data();
    if (!whole_costs_) {
      double sum = 0;
      for (size_t i = 0; i < n; ++i) sum += m[o[i]];
      return sum;
    }
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
      s0 += m[o[i]];
      s1 += m[o[i + 1]];
      s2 += m[o[i + 2]];
      s3 += m[o[i + 3]];
    }
    for (; i < n; ++i) s0 += m[o[i]];
    return (s0 + s1) + (s2 + s3);
  }

  static bool whole_and_small(const std::vector<double>& r) {
    double total = 0;
    for (double x : r) {
      if (!(x >= 0) || x != std::floor(x)) return false;
      total += x;
    }
    return total < 0x1p53;
  }

  void set_marks(std::vector<double>& marks, int32_t cell, bool on) const {
    for (uint32_t o : pvs_[cell]) marks[o] = on ? r_[o] : 0.0;
  }

  double merged_delta(const MergeNode& nx, const MergeNode& ny, double merged) const {
    return ((nx.weight + ny.weight) * merged - nx.weight * nx.pvs_cost - ny.weight * ny.pvs_cost) / W_;
  }

  /// delta(x, y) with the pixel term: r(x + y) of the united PVS over the united bounds.
  double delta_united(const MergeHistory& h, int32_t x, int32_t y) const {
    const MergeNode &nx = h.nodes[x], &ny = h.nodes[y];
    Box3 bounds = nx.bounds;
    bounds.extend(ny.bounds);
    return merged_delta(nx, ny, pvs_cost(unite_sorted(pvs_[x], pvs_[y]), bounds));
  }

  const Scene& scene_;
  const CellPartition& p_;
  const CostModel& model_;
  const std::vector<double> r_;
  const bool whole_costs_;  ///< every r(o) whole and their total below 2^53: sums are exact in any order
  tbb::enumerable_thread_specific<std::vector<double>> marks_;  ///< r(o) of a marked cell's objects, else 0
  double W_ = 1;
  size_t alive_ = 0;
  double cost_ = 0;
  bool constrained_ = false;
  std::vector<int32_t> block_;  ///< per MHT node, with a barrier
  std::vector<std::vector<uint32_t>> pvs_;  ///< per MHT node, while it is a current cell
  std::vector<std::vector<int32_t>> adjacent_;  ///< per MHT node, its current neighbours, sorted
};

ViewCellSet make_set(const MergeHistory& h, size_t k, std::string rule) {
  ViewCellSet set;
  set.cells = h.cut_after(k);
  set.cost = h.cost_with(h.leaf_count - k);
  for (int32_t c : set.cells) {
    set.pvs_entries += h.nodes[c].pvs_size;
    set.pvs_bytes += approx_pvs_bytes(h.nodes[c].pvs_size);
  }
  set.rule = std::move(rule);
  return set;
}

}  // namespace

MergeHistory merge_cells(const Scene& scene, const CellPartition& partition, const CostModel& model,
                         const MergeConfig& config) {
  const size_t L = partition.size();
  if (L == 0) throw Error("nothing to merge: the partition has no cells");
  if (partition.volume.size() != L || partition.bounds.size() != L || partition.pvs.size() != L)
    throw Error("the partition's per-cell arrays differ in length");
  for (size_t i = 0; i < L; ++i) {
    if (!(partition.weight[i] >= 0) || !std::isfinite(partition.weight[i]))
      throw Error("cell " + std::to_string(i) + " has an invalid weight (" + std::to_string(partition.weight[i]) +
                  ", volume " + std::to_string(partition.volume[i]) + ")");
    for (size_t k = 0; k < partition.pvs[i].size(); ++k)
      if (partition.pvs[i][k] >= scene.objects.size() || (k && partition.pvs[i][k] <= partition.pvs[i][k - 1]))
        throw Error("the PVS of cell " + std::to_string(i) + " is not a sorted list of the scene's objects");
  }
  for (const auto& [a, b] : partition.neighbours)
    if (a >= L || b >= L) throw Error("a neighbour pair names a cell that does not exist");
  model.validate();
  return Merger(scene, partition, model).run(config);
}

ViewCellSet extract_by_count(const MergeHistory& h, size_t count) {
  if (count < h.min_cells() || count > h.leaf_count)
    throw Error("cannot extract " + std::to_string(count) + " cells: the merge history holds " +
                std::to_string(h.min_cells()) + " to " + std::to_string(h.leaf_count));
  return make_set(h, h.leaf_count - count, "exactly " + std::to_string(count) + " cells");
}

ViewCellSet extract_by_memory(const MergeHistory& h, uint64_t bytes) {
  // Start from the coarsest cut and undo merges, the last first, while the budget allows.
  size_t k = h.merges();
  uint64_t used = 0;
  for (int32_t c : h.cut_after(k)) used += approx_pvs_bytes(h.nodes[c].pvs_size);
  if (used > bytes)
    throw Error("a PVS budget of " + std::to_string(bytes) + " bytes is too small: the coarsest " +
                std::to_string(h.min_cells()) + " cell(s) need " + std::to_string(used));
  while (k > 0) {
    const MergeNode& m = h.nodes[h.leaf_count + k - 1];
    const uint64_t next = used - approx_pvs_bytes(m.pvs_size) + approx_pvs_bytes(h.nodes[m.child[0]].pvs_size) +
                          approx_pvs_bytes(h.nodes[m.child[1]].pvs_size);
    if (next > bytes) break;
    used = next;
    --k;
  }
  ViewCellSet set = make_set(h, k, "most cells within " + std::to_string(bytes) + " bytes of PVS");
  VC_CHECK(set.pvs_bytes == used);
  return set;
}

ViewCellSet extract_by_cost_ratio(const MergeHistory& h, double ratio) {
  if (!(ratio >= 1.0) || !std::isfinite(ratio)) throw Error("the cost ratio must be a number >= 1");
  const double limit = ratio * h.initial_cost;
  size_t k = 0;  // the most merges whose cost stays within the limit
  for (size_t j = 1; j <= h.merges(); ++j)
    if (h.cost_after[j - 1] <= limit) k = j;
  return make_set(h, k, "fewest cells within " + std::to_string(ratio) + " x the cost of the elementary cells");
}

}  // namespace viewcells
