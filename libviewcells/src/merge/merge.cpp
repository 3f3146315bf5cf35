// View space merging (view-cell-construction paper, section 4.3): greedy merging of neighbouring
// cells by the least increase in expected render cost (history.cpp reads what it made;
// extract.cpp cuts it, section 5.1).
//
// The neighbour graph is a sorted neighbour list per merge-history node id: merging x and y
// adds node z (the largest id so far, so appending it keeps every list sorted) with the union
// of their neighbours and clears x and y. The queue (PairQueue) gives the least (delta, x, y)
// among the pairs of current neighbours; pairs whose x or y has merged since are dropped when
// met, so nothing is ever rescanned. delta needs only the objects the two PVSs share when the
// object costs do not depend on the cell (c = 0): r(x + y) = r(x) + r(y) - r(x n y). One
// cell's objects are marked with their r(o) in an array over the objects, and each partner's
// list sums its marks, adding 0 for the objects not shared: in ascending order the same
// additions as walking the two lists together, without the walk's unpredictable branches; with
// whole costs, integer sums that are exact (Merger::shared_cost).
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

namespace {

struct Entry {
  double delta;
  int32_t x, y;  // x < y
  /// r(x + y) as evaluated, when it is bitwise what summing the united PVS gives (whole costs,
  /// or the pixel term, which sums the united PVS itself); else NaN.
  double merged = std::numeric_limits<double>::quiet_NaN();
};
struct Later {  // min-heap on delta; ties: smaller ids first
  bool operator()(const Entry& p, const Entry& q) const {
    if (p.delta != q.delta) return p.delta > q.delta;
    return p.x != q.x ? p.x > q.x : p.y > q.y;
  }
};

/// The pairs that may merge next, kept in groups of pairs that share a cell (the pairs one
/// merge created, all with the new cell; or a cell's pairs with the cells of larger ids). The
/// heap holds one entry per group, its least pair when it was pushed: as pairs never change
/// cost, only die when a side merges, that entry is at most every live pair of its group. A
/// popped entry whose pair has died sends its group back with its least live pair; one whose
/// pair lives is the least live pair of all, the pair the one heap of every pair would give
/// (ties broken alike), and merging it kills the rest of its group. The heap thus holds about
/// one entry per cell, not one per pair ever evaluated.
class PairQueue {
 public:
  void clear() {
    heap_.clear();
    pool_.clear();
    groups_.clear();
  }
  /// Adds evaluated pairs that all share one cell.
  void add(const std::vector<Entry>& pairs, size_t begin, size_t end) {
    if (begin == end) return;
    const size_t group = groups_.size();
    groups_.push_back({pool_.size(), pool_.size() + (end - begin)});
    pool_.insert(pool_.end(), pairs.begin() + static_cast<std::ptrdiff_t>(begin),
                 pairs.begin() + static_cast<std::ptrdiff_t>(end));
    push_least(group, [](int32_t) { return true; });
  }

  /// Adds evaluated pairs sorted by their first cell: a group per first cell.
  void add_by_first(const std::vector<Entry>& pairs) {
    for (size_t b = 0, e = 0; b < pairs.size(); b = e) {
      for (e = b; e < pairs.size() && pairs[e].x == pairs[b].x; ++e) {
      }
      add(pairs, b, e);
    }
  }

  /// The least pair whose two cells `alive` accepts, if any; `stale` counts the dead pairs
  /// popped on the way.
  template <class Alive>
  std::optional<Entry> pop(const Alive& alive, uint64_t& stale) {
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), later_top);
      const Top top = heap_.back();
      heap_.pop_back();
      if (alive(top.pair.x) && alive(top.pair.y)) return top.pair;
      ++stale;
      push_least(top.group, alive);
    }
    return std::nullopt;
  }

 private:
  struct Top {
    Entry pair;
    size_t group;
  };
  static bool later_top(const Top& p, const Top& q) { return Later{}(p.pair, q.pair); }

  /// Drops the group's dead pairs and pushes its least live one, if any.
  template <class Alive>
  void push_least(size_t group, const Alive& alive) {
    auto& [begin, end] = groups_[group];
    size_t kept = begin;
    for (size_t i = begin; i < end; ++i)
      if (alive(pool_[i].x) && alive(pool_[i].y)) pool_[kept++] = pool_[i];
    end = kept;
    if (begin == end) return;
    size_t least = begin;
    for (size_t i = begin + 1; i < end; ++i)
      if (Later{}(pool_[least], pool_[i])) least = i;
    heap_.push_back({pool_[least], group});
    std::push_heap(heap_.begin(), heap_.end(), later_top);
  }

  std::vector<Top> heap_;
  std::vector<Entry> pool_;                         ///< every group's pairs, one group after another
  std::vector<std::pair<size_t, size_t>> groups_;  ///< [begin, end) of each group's live pairs in pool_
};

/// r(o) of a marked cell's objects, else 0: whole numbers, or doubles (see Merger::shared_cost).
struct Marks {
  std::vector<uint32_t> whole;
  std::vector<double> cost;
};

/// What every merge of one partition reads and none changes: the object costs and, with narrow
/// ids, the partition's PVSs as Id.
template <class Id>
struct MergeInput {
  static constexpr bool kWide = std::is_same_v<Id, uint32_t>;
  MergeInput(const Scene& s, const CellPartition& partition, const CostModel& m)
      : scene(s), p(partition), model(m), r(per_object_costs(s, m)), whole_costs(whole_and_small(r)) {
    if constexpr (!kWide) {
      VC_CHECK(!m.pixel_term() && s.objects.size() <= size_t{1} << 16);
      leaf_lists.resize(p.size());
      tbb::parallel_for(size_t{0}, p.size(), [&](size_t i) {
        leaf_lists[i].assign(p.pvs[i].begin(), p.pvs[i].end());  // each id < 2^16: checked above
      });
    }
  }
  const Scene& scene;
  const CellPartition& p;
  const CostModel& model;
  const std::vector<double> r;
  const bool whole_costs;  ///< every r(o) whole, below 2^32, their total below 2^53: exact sums
  std::vector<std::vector<Id>> leaf_lists;  ///< narrow ids only: the partition's PVSs as Id
};

/// Per-thread scratch marks; a copy of a merger starts with none of its own.
struct MergeScratch {
  MergeScratch() = default;
  MergeScratch(const MergeScratch&) {}
  MergeScratch& operator=(const MergeScratch&) = delete;
  tbb::enumerable_thread_specific<Marks> marks;
  Marks one_cell;
};

/// Greedy merging with PVSs as sorted lists of Id: uint16_t halves the bytes that pair costs
/// read when the scene has at most 65,536 objects and no pixel term (whose costs need the
/// shared code's uint32_t lists); uint32_t otherwise. The merges are the same either way.
/// A merger is the state of one history being built (begin, then prefix merges, then the
/// greedy ones); a copy goes on from the same state (merge_cells_sharing_prefix).
template <class Id>
class Merger {
 public:
  explicit Merger(const MergeInput<Id>& in) : in_(in) {}
  Merger(const Merger&) = default;

  MergeHistory run(const MergeConfig& config) {
    const auto start = std::chrono::steady_clock::now();
    begin();
    const size_t L = in_.p.size(), target = std::max<size_t>(1, config.min_cells);
    Progress progress("merging", L > target ? L - target : 0);
    prefix(config.prefix, 0, config.prefix.size(), target, config.show_progress ? &progress : nullptr);
    return finish(config, start, config.show_progress ? &progress : nullptr);
  }

  /// The elementary cells, each its own current cell.
  void begin() {
    const CellPartition& p = in_.p;
    const size_t L = p.size();
    MergeHistory& h = h_;
    h.leaf_count = static_cast<uint32_t>(L);
    h.nodes.resize(L);
    pvs_.resize(2 * L);
    adjacent_.assign(2 * L, {});
    has_merged_.assign(2 * L, 0);
    for (size_t i = 0; i < L; ++i) {
      MergeNode& n = h.nodes[i];
      n.weight = p.weight[i];
      n.volume = p.volume[i];
      n.bounds = p.bounds[i];
      n.pvs_cost = pvs_cost(list(static_cast<int32_t>(i)), n.bounds);
      n.pvs_size = static_cast<uint32_t>(p.pvs[i].size());
      h.total_weight += n.weight;
    }
    if (!(h.total_weight > 0)) throw Error("the cells to merge have no weight");
    W_ = h.total_weight;
    for (size_t i = 0; i < L; ++i) h.initial_cost += h.nodes[i].weight / W_ * h.nodes[i].pvs_cost;
    for (const auto& [a, b] : p.neighbours)
      if (a != b) {
        adjacent_[a].push_back(static_cast<int32_t>(b));
        adjacent_[b].push_back(static_cast<int32_t>(a));
      }
    for (std::vector<int32_t>& list : adjacent_) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    alive_ = L;
    cost_ = h.initial_cost;
  }

  /// Prefix merges [from, to) of `merges`, while more than `target` cells remain.
  void prefix(const std::vector<std::pair<int32_t, int32_t>>& merges, size_t from, size_t to, size_t target,
              Progress* progress) {
    std::vector<int32_t> around;
    for (size_t j = from; j < to && alive_ > target; ++j) {
      const auto [x, y] = merges[j];
      check_prefix_pair(x, y);
      merge(x, y, around, std::numeric_limits<double>::quiet_NaN());
      if (progress) progress->advance(1);
    }
  }

  /// Greedy merging (with the config's blocks and barrier) down to its min_cells: the history.
  MergeHistory finish(const MergeConfig& config, std::chrono::steady_clock::time_point start, Progress* progress) {
    MergeHistory& h = h_;
    const size_t L = in_.p.size(), target = std::max<size_t>(1, config.min_cells);
    if (!config.block.empty()) {
      if (config.block.size() != L) throw Error("the merge blocks do not match the partition");
      block_.assign(2 * L, -1);
      for (size_t i = 0; i < L; ++i) block_[i] = config.block[i];
      for (size_t k = L; k < h.nodes.size(); ++k) block_[k] = block_[h.nodes[k].child[0]];
    }
    constrained_ = !config.block.empty() && alive_ > config.barrier_cells;
    PairQueue queue;
    queue.add_by_first(all_pairs());
    auto alive = [this](int32_t n) { return has_merged_[static_cast<size_t>(n)] == 0; };
    std::vector<Entry> fresh;
    std::vector<int32_t> around;
    while (alive_ > target) {
      const std::optional<Entry> next = queue.pop(alive, h.stats.stale);
      if (!next) {
        if (!constrained_) break;
        constrained_ = false;  // blocks that cannot merge further: the barrier is lifted
        queue.clear();
        queue.add_by_first(all_pairs());
        continue;
      }
      const Entry& e = *next;
      const int32_t z = merge(e.x, e.y, around, e.merged);
      if (constrained_) block_[z] = block_[e.x];
      if (progress) progress->advance(1);
      if (constrained_ && alive_ <= config.barrier_cells) {
        constrained_ = false;  // at the barrier: every neighbouring pair from now on
        queue.clear();
        queue.add_by_first(all_pairs());
        continue;
      }
      fresh.clear();
      for (int32_t n : around)
        if (allowed(n, z)) fresh.push_back({0.0, n, z});
      evaluate(fresh, &Entry::y);
      queue.add(fresh, 0, fresh.size());
    }
    if (progress) progress->finish();
    h.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return std::move(h_);
  }

 private:
  bool allowed(int32_t x, int32_t y) const { return !constrained_ || block_[x] == block_[y]; }

  /// Every allowed neighbouring pair of the current cells, evaluated.
  std::vector<Entry> all_pairs() {
    std::vector<Entry> entries;
    for (size_t v = 0; v < h_.nodes.size(); ++v)
      for (int32_t w : adjacent_[v])
        if (static_cast<int32_t>(v) < w && allowed(static_cast<int32_t>(v), w))
          entries.push_back({0.0, static_cast<int32_t>(v), w});
    evaluate(entries, &Entry::x);
    return entries;
  }

  void check_prefix_pair(int32_t x, int32_t y) const {
    const int32_t n = static_cast<int32_t>(h_.nodes.size());
    if (x < 0 || y < 0 || x >= n || y >= n || x == y || h_.nodes[x].parent >= 0 || h_.nodes[y].parent >= 0)
      throw Error("a prefix merge names cells that are not current cells (" + std::to_string(x) + ", " +
                  std::to_string(y) + ")");
  }

  /// Merges current cells x and y into a new node z; `around` gets z's neighbours. `merged`:
  /// r(z) if already known exactly (see Entry), else NaN.
  int32_t merge(int32_t x, int32_t y, std::vector<int32_t>& around, double merged) {
    MergeHistory& h = h_;
    const int32_t z = static_cast<int32_t>(h.nodes.size());
    MergeNode node;
    node.child[0] = x;
    node.child[1] = y;
    node.weight = h.nodes[x].weight + h.nodes[y].weight;
    node.volume = h.nodes[x].volume + h.nodes[y].volume;
    node.bounds = h.nodes[x].bounds;
    node.bounds.extend(h.nodes[y].bounds);
    pvs_[z] = unite_sorted(list(x), list(y));
    node.pvs_cost = std::isnan(merged) ? pvs_cost(pvs_[z], node.bounds) : merged;
    node.pvs_size = static_cast<uint32_t>(pvs_[z].size());
    // The recorded cost uses the merged cell's actual r(PVS), not the queued estimate.
    cost_ += (node.weight * node.pvs_cost - h.nodes[x].weight * h.nodes[x].pvs_cost -
              h.nodes[y].weight * h.nodes[y].pvs_cost) / W_;
    h.nodes.push_back(node);
    h.nodes[x].parent = z;
    has_merged_[static_cast<size_t>(x)] = has_merged_[static_cast<size_t>(y)] = 1;
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
    pvs_[x] = {};  // (the elementary cells' lists stay the partition's)
    pvs_[y] = {};
    return z;
  }

  /// The PVS of current cell n: an elementary cell's is the partition's own.
  const std::vector<Id>& list(int32_t n) const {
    const size_t i = static_cast<size_t>(n);
    if constexpr (kWide) {
      return i < in_.p.size() ? in_.p.pvs[i] : pvs_[i];
    } else {
      return i < in_.p.size() ? in_.leaf_lists[i] : pvs_[i];
    }
  }

  /// r(PVS): viewcells::pvs_cost, or its sum without the pixel term, added in the same order.
  double pvs_cost(const std::vector<Id>& pvs, const Box3& bounds) const {
    if constexpr (kWide) {
      return viewcells::pvs_cost(in_.scene, in_.r, in_.model, pvs, bounds);
    } else {
      if (in_.whole_costs) return whole_pvs_cost(in_.r, pvs);
      double c = 0;
      for (Id o : pvs) c += in_.r[o];
      return c;
    }
  }

  /// delta(x, y) for every entry. Without the pixel term, the cell on the entries' `shared`
  /// side (x or y) has its objects marked once per run of entries that share it, and the
  /// other side sums the marks. When every entry shares that cell (the pairs of a merge's new
  /// cell), it is marked once, in marks that the tasks share.
  void evaluate(std::vector<Entry>& entries, int32_t Entry::*shared) {
    MergeHistory& h = h_;
    h.stats.evaluations += entries.size();
    if (entries.empty()) return;
    size_t work = 0;  // list entries read: small sets run without tasks
    for (const Entry& e : entries) work += list(e.x).size() + list(e.y).size();
    const size_t grain = work > (size_t{1} << 13) ? std::max<size_t>(1, entries.size() / 4) : entries.size() + 1;
    const int32_t first = entries.front().*shared;
    const bool one_cell =
        std::all_of(entries.begin(), entries.end(), [&](const Entry& e) { return e.*shared == first; });
    const bool marking = !in_.model.pixel_term();
    if (marking && one_cell) set_marks(scratch_.one_cell, first, true);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, entries.size(), grain), [&](const tbb::blocked_range<size_t>& r) {
      if (!marking) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          Entry& e = entries[i];
          const MergeNode &nx = h.nodes[e.x], &ny = h.nodes[e.y];
          Box3 bounds = nx.bounds;
          bounds.extend(ny.bounds);
          e.merged = pvs_cost(unite_sorted(list(e.x), list(e.y)), bounds);
          e.delta = merged_delta(nx, ny, e.merged);
        }
        return;
      }
      Marks& marks = one_cell ? scratch_.one_cell : scratch_.marks.local();
      int32_t marked = one_cell ? first : -1;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        Entry& e = entries[i];
        const int32_t s = e.*shared, other = s == e.x ? e.y : e.x;
        if (s != marked) {
          if (marked >= 0) set_marks(marks, marked, false);
          set_marks(marks, s, true);
          marked = s;
        }
        const double common = shared_cost(marks, list(other));
        const MergeNode &nx = h.nodes[e.x], &ny = h.nodes[e.y];
        const double merged = nx.pvs_cost + ny.pvs_cost - common;
        e.delta = merged_delta(nx, ny, merged);
        if (in_.whole_costs) e.merged = merged;  // exact
      }
      if (!one_cell && marked >= 0) set_marks(marks, marked, false);
    });
    if (marking && one_cell) set_marks(scratch_.one_cell, first, false);
  }

  /// r(x n y): the marks of x summed over y's objects. When every r(o) is a whole number below
  /// 2^32 and their total is below 2^53 (the default model: max(a, b t_o) with whole a and b),
  /// the marks are integers and their sum is exact, so it is bitwise the sum in any order;
  /// otherwise the doubles are added in ascending object order, one after the other.
  double shared_cost(const Marks& marks, const std::vector<Id>& list) const {
    if (in_.whole_costs) {
      const uint32_t* m = marks.whole.data();
      uint64_t sum = 0;
      for (uint32_t o : list) sum += m[o];
      return static_cast<double>(sum);
    }
    const double* m = marks.cost.data();
    double sum = 0;
    for (uint32_t o : list) sum += m[o];
    return sum;
  }

  void set_marks(Marks& marks, int32_t cell, bool on) const {
    const std::vector<double>& r = in_.r;
    if (in_.whole_costs) {
      if (marks.whole.empty()) marks.whole.assign(r.size(), 0);
      for (Id o : list(cell)) marks.whole[o] = on ? static_cast<uint32_t>(r[o]) : 0;
    } else {
      if (marks.cost.empty()) marks.cost.assign(r.size(), 0.0);
      for (Id o : list(cell)) marks.cost[o] = on ? r[o] : 0.0;
    }
  }

  double merged_delta(const MergeNode& nx, const MergeNode& ny, double merged) const {
    return ((nx.weight + ny.weight) * merged - nx.weight * nx.pvs_cost - ny.weight * ny.pvs_cost) / W_;
  }

  static constexpr bool kWide = MergeInput<Id>::kWide;
  const MergeInput<Id>& in_;
  MergeScratch scratch_;
  MergeHistory h_;  ///< the history so far
  double W_ = 1;
  size_t alive_ = 0;
  double cost_ = 0;
  bool constrained_ = false;
  std::vector<int32_t> block_;  ///< per MHT node, with a barrier
  std::vector<std::vector<Id>> pvs_;  ///< per merged MHT node, while it is a current cell
  std::vector<std::vector<int32_t>> adjacent_;  ///< per MHT node, its current neighbours, sorted
  std::vector<uint8_t> has_merged_;  ///< per MHT node, 1 once merged: what the queue looks up
};


}  // namespace

namespace {

void check_merge_input(const Scene& scene, const CellPartition& partition, const CostModel& model) {
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
}

bool narrow_ids(const Scene& scene, const CostModel& model) {
  return !model.pixel_term() && scene.objects.size() <= size_t{1} << 16;
}

/// merge_cells_sharing_prefix with ids of type Id: one merger walks the longest prefix; at each
/// config's end of it, a copy of the walker goes on greedily as that config says, in a task.
template <class Id>
void merge_sharing_prefix(const MergeInput<Id>& in, const std::vector<MergeConfig>& configs,
                          const std::function<void(size_t, MergeHistory)>& done) {
  if (configs.empty()) return;
  const size_t L = in.p.size();
  size_t longest = 0;
  for (size_t i = 1; i < configs.size(); ++i)
    if (configs[i].prefix.size() > configs[longest].prefix.size()) longest = i;
  const std::vector<std::pair<int32_t, int32_t>>& all = configs[longest].prefix;
  // Where each config leaves the prefix: where run() would (at its end, or where its target is).
  std::vector<std::pair<size_t, size_t>> order;  // (prefix merges, config)
  for (size_t i = 0; i < configs.size(); ++i) {
    const MergeConfig& c = configs[i];
    if (!std::equal(c.prefix.begin(), c.prefix.end(), all.begin()))
      throw Error("merge_cells_sharing_prefix: each prefix must be the first merges of the longest one");
    const size_t target = std::max<size_t>(1, c.min_cells);
    order.emplace_back(std::min(c.prefix.size(), L > target ? L - target : 0), i);
  }
  std::sort(order.begin(), order.end());
  // A pipeline: the walker's state at one end, copied by its configs in parallel while the
  // walker goes on to the next; at most kInFlight states are held at once.
  constexpr size_t kInFlight = 2;
  struct Group {
    std::unique_ptr<const Merger<Id>> state;
    size_t begin = 0, end = 0;  ///< its configs: order[begin, end)
  };
  Merger<Id> walker(in);
  walker.begin();
  size_t next = 0, at = 0;
  tbb::parallel_pipeline(
      kInFlight,
      tbb::make_filter<void, std::shared_ptr<Group>>(
          tbb::filter_mode::serial_in_order,
          [&](tbb::flow_control& fc) -> std::shared_ptr<Group> {
            if (next == order.size()) {
              fc.stop();
              return nullptr;
            }
            auto g = std::make_shared<Group>();
            const size_t to = order[next].first;
            walker.prefix(all, at, to, 1, nullptr);
            at = to;
            g->state = std::make_unique<const Merger<Id>>(walker);
            g->begin = next;
            while (next < order.size() && order[next].first == to) ++next;
            g->end = next;
            return g;
          }) &
          tbb::make_filter<std::shared_ptr<Group>, void>(
              tbb::filter_mode::parallel, [&](const std::shared_ptr<Group>& g) {
                tbb::parallel_for(g->begin, g->end, [&](size_t k) {
                  const auto start = std::chrono::steady_clock::now();
                  Merger<Id> m(*g->state);
                  const size_t i = order[k].second;
                  done(i, m.finish(configs[i], start, nullptr));
                });
              }));
}

}  // namespace

MergeHistory merge_cells(const Scene& scene, const CellPartition& partition, const CostModel& model,
                         const MergeConfig& config) {
  check_merge_input(scene, partition, model);
  if (narrow_ids(scene, model)) {
    const MergeInput<uint16_t> in(scene, partition, model);
    return Merger<uint16_t>(in).run(config);
  }
  const MergeInput<uint32_t> in(scene, partition, model);
  return Merger<uint32_t>(in).run(config);
}

void merge_cells_sharing_prefix(const Scene& scene, const CellPartition& partition, const CostModel& model,
                                const std::vector<MergeConfig>& configs,
                                const std::function<void(size_t, MergeHistory)>& done) {
  check_merge_input(scene, partition, model);
  if (narrow_ids(scene, model)) {
    merge_sharing_prefix(MergeInput<uint16_t>(scene, partition, model), configs, done);
  } else {
    merge_sharing_prefix(MergeInput<uint32_t>(scene, partition, model), configs, done);
  }
}

}  // namespace viewcells
