/// The evaluator (view-cell-construction paper, section 6.1): c(S) at every cell count from
/// independent samples.
#include "viewcells/eval/evaluate.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <memory>
#include <optional>

#include "bsp/segment_walk.h"
#include "viewcells/core/error.h"
#include "viewcells/sampling/segments.h"

namespace viewcells {

namespace {

/// What a segment's walk reads of each node of a subdivision, in 24 bytes (the node and its
/// plane are two cache lines apart in the Subdivision): the same walk, the same leaves, about
/// half the memory reads. The evaluation walks every evaluation segment down every tree.
class WalkTree {
 public:
  /// The inner nodes in depth-first order (a node's first child right after it); a child that
  /// is a leaf is named by ~(its leaf ordinal), so that reaching a leaf reads no node: the walk
  /// reads only the inner nodes, half as many bytes as the whole tree (on the city's 50k
  /// cells, 1.2 MB against 2.4 MB, about what the core's own cache holds).
  explicit WalkTree(const Subdivision& s) : s_(s) {
    std::vector<int32_t> id(s.nodes.size(), -1), order;
    std::vector<int32_t> stack{0};
    while (!stack.empty()) {
      const int32_t n = stack.back();
      stack.pop_back();
      const BspNode& bn = s.nodes[n];
      if (bn.plane < 0) {
        id[n] = ~static_cast<int32_t>(leaf_nodes_.size());
        leaf_nodes_.push_back(n);
        continue;
      }
      id[n] = static_cast<int32_t>(order.size());
      order.push_back(n);
      stack.push_back(bn.child[1]);
      stack.push_back(bn.child[0]);
    }
    root_ = id[0];
    nodes_.resize(order.size());
    for (size_t i = 0; i < order.size(); ++i) {
      const BspNode& bn = s.nodes[order[i]];
      Node& w = nodes_[i];
      const Plane& p = s.planes[bn.plane];
      w.plane = bn.plane;
      w.axis = p.axis;
      w.offset = p.offset;
      w.child[0] = id[bn.child[0]];
      w.child[1] = id[bn.child[1]];
    }
  }
  int32_t root() const { return root_; }
  /// Whether walk node n is a leaf, and which leaf (0 .. leaves() - 1).
  static bool leaf(int32_t n) { return n < 0; }
  static uint32_t leaf_ordinal(int32_t n) { return static_cast<uint32_t>(~n); }
  size_t leaves() const { return leaf_nodes_.size(); }
  /// The BSP node of leaf ordinal k.
  int32_t leaf_node(size_t k) const { return leaf_nodes_[k]; }
  int axis(int32_t n) const { return nodes_[n].axis; }
  double offset(int32_t n) const { return nodes_[n].offset; }
  const Plane& plane(int32_t n) const { return s_.planes[nodes_[n].plane]; }
  int32_t child(int32_t n, int k) const { return nodes_[n].child[k]; }

 private:
  struct Node {
    double offset = 0;
    int32_t child[2] = {-1, -1};
    int32_t axis = -1, plane = -1;
  };
  const Subdivision& s_;
  std::vector<Node> nodes_;
  std::vector<int32_t> leaf_nodes_;
  int32_t root_ = 0;
};

/// One thread's objects per leaf (by ordinal), as the walks meet them: duplicates are the rule
/// (segments in Z-order meet the same leaves with the same objects), so a leaf skips the pair of
/// objects it got last, and an object equal to its list's last; a list is sorted and made
/// unique in place whenever it doubles past 4,096 entries.
struct LeafLists {
  explicit LeafLists(size_t leaves) : lists(leaves), last(leaves, ~uint64_t{0}), limit(leaves, kFirstLimit) {}
  void add(uint32_t leaf, uint32_t a, uint32_t b) {
    const uint64_t key = (uint64_t{a} << 32) | b;
    if (last[leaf] == key) return;
    last[leaf] = key;
    std::vector<uint32_t>& l = lists[leaf];
    for (uint32_t o : {a, b})
      if (o != kNoObject && (l.empty() || l.back() != o)) l.push_back(o);
    if (l.size() >= limit[leaf]) {
      std::sort(l.begin(), l.end());
      l.erase(std::unique(l.begin(), l.end()), l.end());
      limit[leaf] = std::max<uint32_t>(kFirstLimit, 2 * static_cast<uint32_t>(l.size()));
    }
  }
  static constexpr uint32_t kFirstLimit = 4096;
  std::vector<std::vector<uint32_t>> lists;
  std::vector<uint64_t> last;    ///< the objects of the segment a leaf got last
  std::vector<uint32_t> limit;   ///< the size at which a list is next made unique
};

/// Every leaf's objects as bits, shared by the threads: a bit is set by an atomic or only where
/// a plain read finds it clear (most of a walk's objects are already in the leaf). The bits
/// are stored per object, over the leaves in the walk tree's depth-first order: the leaves a
/// segment crosses one after another are mostly near in that order, so that its two objects'
/// bits for them share a few cache lines (stored per leaf, over the objects, every leaf cost a
/// line of its own for each object). Read out a block of 512 leaves at a time, object by
/// object, so the lists come out sorted and unique.
class LeafBits {
 public:
  LeafBits(size_t leaves, size_t objects) : leaves_(leaves), words_((leaves + 63) / 64), bits_(objects * words_, 0) {}
  static size_t bytes(size_t leaves, size_t objects) { return objects * ((leaves + 63) / 64) * 8; }
  void add(uint32_t leaf, uint32_t o) {
    if (o == kNoObject) return;
    uint64_t* w = &bits_[static_cast<size_t>(o) * words_ + leaf / 64];
    const uint64_t m = uint64_t{1} << (leaf % 64);
    if (!(__atomic_load_n(w, __ATOMIC_RELAXED) & m)) __atomic_fetch_or(w, m, __ATOMIC_RELAXED);
  }
  void clear() { std::fill(bits_.begin(), bits_.end(), 0); }
  /// Every leaf's list, by leaf ordinal, to out[node(ordinal)].
  template <class Node>
  void lists(std::vector<std::vector<uint32_t>>& out, Node&& node) const {
    constexpr size_t kBlock = 8;  // words: one cache line of each object's bits
    const size_t objects = words_ ? bits_.size() / words_ : 0;
    tbb::parallel_for(size_t{0}, (words_ + kBlock - 1) / kBlock, [&](size_t block) {
      const size_t first = block * kBlock, last = std::min(words_, first + kBlock);
      // f(object, leaf ordinal) for every bit set in the block, object by object.
      auto each_bit = [&](auto&& f) {
        for (size_t o = 0; o < objects; ++o)
          for (size_t k = first; k < last; ++k)
            for (uint64_t w = bits_[o * words_ + k]; w; w &= w - 1) f(o, k * 64 + static_cast<size_t>(__builtin_ctzll(w)));
      };
      size_t count[kBlock * 64] = {};  // first each list's size, so that each is allocated once
      each_bit([&](size_t, size_t leaf) { ++count[leaf - first * 64]; });
      for (size_t j = 0; j < (last - first) * 64 && first * 64 + j < leaves_; ++j) out[node(first * 64 + j)].reserve(count[j]);
      each_bit([&](size_t o, size_t leaf) { out[node(leaf)].push_back(static_cast<uint32_t>(o)); });
    });
  }

 private:
  size_t leaves_, words_;
  std::vector<uint64_t> bits_;
};

/// Walks segment order[k], k in r, down `tree`, calling add(leaf ordinal, object a, object b)
/// for every leaf it has length in.
template <class Add>
void walk_segments(const WalkTree& tree, const SegmentSet& eval, const std::vector<size_t>& order,
                   const tbb::blocked_range<size_t>& r, Add&& add) {
  std::vector<std::tuple<int32_t, double, double>> stack;
  for (size_t k = r.begin(); k < r.end(); ++k) {
    const size_t i = order[k];
    const uint32_t a = eval.object_a[i], b = eval.object_b[i];  // read once, not at every leaf
    bsp_detail::walk_segment(
        tree, eval.a(i), eval.b(i), stack,
        [&](int32_t n, double, double) {
          if (!WalkTree::leaf(n)) return false;
          add(WalkTree::leaf_ordinal(n), a, b);
          return true;
        },
        tree.root());
  }
}

/// The largest object id of the segments, plus one.
uint32_t objects_seen(const SegmentSet& eval) {
  uint32_t objects = 0;
  for (size_t i = 0; i < eval.size(); ++i)
    for (uint32_t o : {eval.object_a[i], eval.object_b[i]})
      if (o != kNoObject) objects = std::max(objects, o + 1);
  return objects;
}

constexpr size_t kMaxBitBytes = size_t{512} << 20;
/// Bits only from 512 objects on: few objects make short lists, which the check of the last
/// pair keeps cheap, so the lists lose nothing measurable there (BENCHMARKS.md, "Decisions
/// measured").
constexpr size_t kMinBitObjects = 512;

/// Whether the automatic gather takes bits for rows of `leaves` x `objects`.
bool bits_pay(size_t leaves, size_t objects) {
  return objects >= kMinBitObjects && LeafBits::bytes(leaves, objects) <= kMaxBitBytes;
}

}  // namespace

struct EvaluationPvs::Impl {
  Impl(const Subdivision& sub, size_t object_count, bool use_bits) : s(sub), tree(sub), objects(object_count) {
    if (use_bits) {
      bits.emplace(tree.leaves(), objects);
    } else {
      lists.resize(s.nodes.size());
    }
  }
  const Subdivision& s;
  WalkTree tree;
  size_t objects;
  std::optional<LeafBits> bits;
  std::vector<std::vector<uint32_t>> lists;  ///< per node, without bits

  void add(const SegmentSet& eval, const std::vector<size_t>& order) {
    if (order.size() != eval.size()) throw Error("evaluation_pvs: the order is not one of the segments");
    if (objects_seen(eval) > objects) throw Error("evaluation_pvs: a segment sees an object the scene does not have");
    const tbb::blocked_range<size_t> all(0, eval.size(), 4096);
    if (bits) {
      tbb::parallel_for(all, [&](const tbb::blocked_range<size_t>& r) {
        walk_segments(tree, eval, order, r, [&](uint32_t leaf, uint32_t a, uint32_t b) {
          bits->add(leaf, a);
          bits->add(leaf, b);
        });
      });
      return;
    }
    tbb::enumerable_thread_specific<LeafLists> per_thread([&] { return LeafLists(tree.leaves()); });
    tbb::parallel_for(all, [&](const tbb::blocked_range<size_t>& r) {
      LeafLists& l = per_thread.local();
      walk_segments(tree, eval, order, r, [&](uint32_t leaf, uint32_t a, uint32_t b) { l.add(leaf, a, b); });
    });
    std::vector<LeafLists*> threads;
    for (LeafLists& l : per_thread) threads.push_back(&l);
    tbb::parallel_for(size_t{0}, tree.leaves(), [&](size_t k) {
      std::vector<uint32_t>& l = lists[tree.leaf_node(k)];
      const auto sorted = static_cast<std::ptrdiff_t>(l.size());  // the sets added before
      for (LeafLists* t : threads) {
        std::vector<uint32_t>& from = t->lists[k];
        if (l.empty()) {
          l.swap(from);
        } else {
          l.insert(l.end(), from.begin(), from.end());
        }
        from = {};
      }
      std::sort(l.begin() + sorted, l.end());
      std::inplace_merge(l.begin(), l.begin() + sorted, l.end());
      l.erase(std::unique(l.begin(), l.end()), l.end());
    });
  }
  std::vector<std::vector<uint32_t>> read() const {
    if (!bits) return lists;
    std::vector<std::vector<uint32_t>> out(s.nodes.size());
    bits->lists(out, [&](size_t k) { return tree.leaf_node(k); });
    return out;
  }
};

EvaluationPvs::EvaluationPvs(const Subdivision& s, size_t objects, LeafGather gather) {
  if (s.nodes.empty()) throw Error("evaluation needs a subdivision");
  if (gather == LeafGather::kAutomatic) gather = bits_pay(s.leaf_count(), objects) ? LeafGather::kBits : LeafGather::kLists;
  impl_ = std::make_unique<Impl>(s, objects, gather == LeafGather::kBits);
}
EvaluationPvs::~EvaluationPvs() = default;
EvaluationPvs::EvaluationPvs(EvaluationPvs&&) noexcept = default;
void EvaluationPvs::add(const SegmentSet& eval, const std::vector<size_t>& order) { impl_->add(eval, order); }
void EvaluationPvs::add(const SegmentSet& eval) { impl_->add(eval, coherent_order(eval, impl_->s.view_box)); }
std::vector<std::vector<uint32_t>> EvaluationPvs::lists() const { return impl_->read(); }
std::vector<std::vector<uint32_t>> EvaluationPvs::take() {
  if (impl_->bits) {
    std::vector<std::vector<uint32_t>> out = impl_->read();
    impl_->bits->clear();
    return out;
  }
  std::vector<std::vector<uint32_t>> out(impl_->s.nodes.size());
  out.swap(impl_->lists);
  return out;
}
bool EvaluationPvs::bits() const { return impl_->bits.has_value(); }

std::vector<std::vector<uint32_t>> evaluation_pvs(const Subdivision& s, const SegmentSet& eval,
                                                  const std::vector<size_t>& order, LeafGather gather) {
  if (s.nodes.empty()) throw Error("evaluation needs a subdivision");
  const uint32_t objects = objects_seen(eval);
  if (gather == LeafGather::kAutomatic) {
    // Rows for every leaf are cleared and read out whatever the segments: only where they are few
    // bytes per segment walked.
    gather = bits_pay(s.leaf_count(), objects) && LeafBits::bytes(s.leaf_count(), objects) <= 64 * eval.size()
                 ? LeafGather::kBits
                 : LeafGather::kLists;
  }
  EvaluationPvs pvs(s, objects, gather);
  pvs.add(eval, order);
  return pvs.take();
}

std::vector<std::vector<uint32_t>> evaluation_pvs(const Subdivision& s, const SegmentSet& eval) {
  // In Z-order of the segments' ends, so that consecutive walks share their nodes and leaves
  // in the cache (on the city's 50k cells, half the time of walking them as sampled).
  return evaluation_pvs(s, eval, coherent_order(eval, s.view_box));
}

double CostCurve::at(uint32_t n) const {
  const auto it = std::lower_bound(cells.begin(), cells.end(), n);
  if (it == cells.end() || *it != n) throw Error("the cost curve has no point at " + std::to_string(n) + " cells");
  return cost[it - cells.begin()];
}

// Children have larger ids than their parent in the BSP, smaller ones in the merge history.
std::vector<double> evaluated_bsp_costs(const Scene& scene, const Subdivision& s,
                                   const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model) {
  if (leaf_pvs.size() != s.nodes.size()) throw Error("evaluation PVSs do not match the subdivision");
  const std::vector<double> base = per_object_costs(scene, model);
  const bool whole = !model.pixel_term() && whole_and_small(base);
  const size_t n = s.nodes.size();
  std::vector<std::vector<uint32_t>> pvs(n);
  std::vector<Box3> bounds(n);
  std::vector<double> r(n, 0.0);
  for (size_t i = n; i-- > 0;) {
    const BspNode& node = s.nodes[i];
    if (node.plane < 0) {
      pvs[i] = leaf_pvs[i];
      if (model.pixel_term()) {
        if (s.cells.size() != n || s.cells[i].empty()) throw Error("the pixel term needs the cells' geometry");
        bounds[i] = s.cells[i].bounds();
      }
    } else {
      pvs[i] = unite_sorted(pvs[node.child[0]], pvs[node.child[1]]);
      bounds[i] = bounds[node.child[0]];
      bounds[i].extend(bounds[node.child[1]]);
      pvs[node.child[0]] = {};
      pvs[node.child[1]] = {};
    }
    r[i] = whole ? whole_pvs_cost(base, pvs[i]) : pvs_cost(scene, base, model, pvs[i], bounds[i]);
  }
  return r;
}

namespace {

/// evaluated_merge_costs with whole object costs and no pixel term, where a bit set over the
/// objects is no larger than the average leaf's PVS list: each live cell's PVS as bits (a
/// merged cell takes over its first child's), r(x + y) = r(x) + r(y) - r(x n y), the common
/// objects read off the words both have set. Exact, so the same values as the lists' sums.
/// With `from` (a cut of a history that `h` begins with, and that history's r), the replay
/// starts at that cut; with `keep`, the cuts after keep->cuts[k].merges merges are recorded.
std::vector<double> evaluated_merge_costs_by_bits(const MergeHistory& h, const std::vector<int32_t>& leaves,
                                                  const std::vector<std::vector<uint32_t>>& leaf_pvs,
                                                  const std::vector<double>& base,
                                                  const MergeReplayCuts::Cut* from = nullptr,
                                                  const std::vector<double>* from_r = nullptr,
                                                  MergeReplayCuts* keep = nullptr) {
  const size_t words = (base.size() + 63) / 64;
  std::vector<uint64_t> whole(base.size());
  for (size_t o = 0; o < base.size(); ++o) whole[o] = static_cast<uint64_t>(base[o]);
  std::vector<uint32_t> slot(h.nodes.size());
  std::vector<double> r(h.nodes.size(), 0.0);
  std::vector<uint64_t> bits;  // per slot
  size_t first = 0;            // the first node to compute
  if (from) {
    first = h.leaf_count + from->merges;
    bits = from->bits;
    for (size_t k = 0; k < from->live.size(); ++k) slot[from->live[k]] = static_cast<uint32_t>(k);
    std::copy(from_r->begin(), from_r->begin() + static_cast<std::ptrdiff_t>(first), r.begin());
  } else {
    bits.assign(static_cast<size_t>(h.leaf_count) * words, 0);
  }
  std::vector<uint8_t> merged;  // per node, when cuts are kept
  size_t next_cut = 0;
  if (keep) merged.assign(h.nodes.size(), 0);
  for (size_t i = first; i < h.nodes.size(); ++i) {
    if (keep && next_cut < keep->cuts.size() && keep->cuts[next_cut].merges + h.leaf_count == i) {
      MergeReplayCuts::Cut& cut = keep->cuts[next_cut++];
      for (size_t n = 0; n < i; ++n)
        if (!merged[n]) {
          cut.live.push_back(static_cast<int32_t>(n));
          const uint64_t* b = &bits[static_cast<size_t>(slot[n]) * words];
          cut.bits.insert(cut.bits.end(), b, b + words);
        }
    }
    const MergeNode& m = h.nodes[i];
    if (m.child[0] < 0) {
      slot[i] = static_cast<uint32_t>(i);  // the leaves' slots, in order
      uint64_t* b = &bits[i * words];
      const std::vector<uint32_t>& list = leaf_pvs[leaves[i]];
      for (uint32_t o : list) b[o >> 6] |= uint64_t{1} << (o & 63);
      r[i] = whole_pvs_cost(base, list);
      continue;
    }
    uint64_t* x = &bits[static_cast<size_t>(slot[m.child[0]]) * words];
    const uint64_t* y = &bits[static_cast<size_t>(slot[m.child[1]]) * words];
    uint64_t common = 0;
    for (size_t k = 0; k < words; ++k) {
      for (uint64_t w = x[k] & y[k]; w; w &= w - 1) common += whole[k * 64 + static_cast<size_t>(__builtin_ctzll(w))];
      x[k] |= y[k];
    }
    slot[i] = slot[m.child[0]];
    r[i] = r[m.child[0]] + r[m.child[1]] - static_cast<double>(common);
    if (keep) merged[m.child[0]] = merged[m.child[1]] = 1;
  }
  return r;
}

/// Whether evaluated_merge_costs works on bit sets for these leaf PVSs (and `base`, the
/// objects' costs, then).
bool merge_costs_by_bits(const Scene& scene, const MergeHistory& h, const std::vector<int32_t>& leaves,
                         const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model,
                         std::vector<double>& base) {
  base = per_object_costs(scene, model);
  if (model.pixel_term() || !whole_and_small(base) || h.leaf_count == 0) return false;
  size_t entries = 0;
  for (int32_t l : leaves) entries += leaf_pvs[l].size();
  const size_t words = (base.size() + 63) / 64;
  return words * sizeof(uint64_t) * h.leaf_count <= entries * sizeof(uint32_t);
}

void check_merge_evaluation(const Subdivision& s, const MergeHistory& h, const std::vector<int32_t>& leaves,
                            const std::vector<std::vector<uint32_t>>& leaf_pvs) {
  if (leaves.size() != h.leaf_count || leaf_pvs.size() != s.nodes.size())
    throw Error("the merge history does not match the subdivision");
}

}  // namespace

std::vector<double> evaluated_merge_costs(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                   const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model) {
  return evaluated_merge_costs(scene, s, h, leaf_pvs, model, MergeReplayCuts{});
}

MergeReplayCuts replay_merge_cuts(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                  const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model,
                                  std::vector<size_t> merges) {
  const std::vector<int32_t> leaves = s.leaves();
  check_merge_evaluation(s, h, leaves, leaf_pvs);
  MergeReplayCuts out;
  out.history = &h;
  out.leaf_pvs = &leaf_pvs;
  std::vector<double> base;
  if (!merge_costs_by_bits(scene, h, leaves, leaf_pvs, model, base)) return out;  // nothing to share
  out.words = (base.size() + 63) / 64;
  std::sort(merges.begin(), merges.end());
  merges.erase(std::unique(merges.begin(), merges.end()), merges.end());
  for (size_t m : merges)
    if (m > 0 && m < h.merges()) out.cuts.push_back({m, {}, {}});
  out.r = evaluated_merge_costs_by_bits(h, leaves, leaf_pvs, base, nullptr, nullptr, &out);
  return out;
}

std::vector<double> evaluated_merge_costs(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                          const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model,
                                          const MergeReplayCuts& from) {
  const std::vector<int32_t> leaves = s.leaves();
  check_merge_evaluation(s, h, leaves, leaf_pvs);
  std::vector<double> base;
  if (!merge_costs_by_bits(scene, h, leaves, leaf_pvs, model, base)) {
    // Lists: each node's PVS the union of its children's (no cuts to start from here).
    const bool whole = !model.pixel_term() && whole_and_small(base);
    std::vector<std::vector<uint32_t>> pvs(h.nodes.size());
    std::vector<double> r(h.nodes.size(), 0.0);
    for (size_t i = 0; i < h.nodes.size(); ++i) {
      const MergeNode& m = h.nodes[i];
      if (m.child[0] < 0) {
        pvs[i] = leaf_pvs[leaves[i]];
      } else {
        pvs[i] = unite_sorted(pvs[m.child[0]], pvs[m.child[1]]);
        pvs[m.child[0]] = {};
        pvs[m.child[1]] = {};
      }
      r[i] = whole ? whole_pvs_cost(base, pvs[i]) : pvs_cost(scene, base, model, pvs[i], m.bounds);
    }
    return r;
  }
  const MergeReplayCuts::Cut* cut = nullptr;
  if (from.history && from.leaf_pvs == &leaf_pvs && from.history->leaf_count == h.leaf_count && from.words == (base.size() + 63) / 64) {
    // The latest cut whose merges h begins with: h's merge nodes compared with from's, in order.
    const MergeHistory& g = *from.history;
    const size_t L = h.leaf_count, common_limit = std::min(h.merges(), g.merges());
    size_t same = 0;
    for (const MergeReplayCuts::Cut& c : from.cuts) {
      if (c.merges > common_limit) break;
      while (same < c.merges && h.nodes[L + same].child[0] == g.nodes[L + same].child[0] &&
             h.nodes[L + same].child[1] == g.nodes[L + same].child[1])
        ++same;
      if (same < c.merges) break;
      cut = &c;
    }
  }
  return evaluated_merge_costs_by_bits(h, leaves, leaf_pvs, base, cut, cut ? &from.r : nullptr);
}

CostCurve subdivision_curve(const Subdivision& s, const std::vector<double>& r) {
  if (r.size() != s.nodes.size()) throw Error("node costs do not match the subdivision");
  const double W = s.nodes[0].weight;
  CostCurve curve;
  double c = r[0];
  curve.cells.push_back(1);
  curve.cost.push_back(c);
  for (size_t k = 0; k < s.splits.size(); ++k) {
    const int32_t n = s.splits[k].node;
    const BspNode& node = s.nodes[n];
    c += (s.nodes[node.child[0]].weight * r[node.child[0]] + s.nodes[node.child[1]].weight * r[node.child[1]] -
          node.weight * r[n]) / W;
    curve.cells.push_back(static_cast<uint32_t>(k + 2));
    curve.cost.push_back(c);
  }
  return curve;
}

CostCurve merge_history_curve(const MergeHistory& h, const std::vector<double>& r) {
  if (r.size() != h.nodes.size()) throw Error("node costs do not match the merge history");
  const double W = h.total_weight;
  std::vector<double> after(h.merges() + 1);  // after[k]: cost after k merges
  double c = 0;
  for (uint32_t i = 0; i < h.leaf_count; ++i) c += h.nodes[i].weight * r[i] / W;
  after[0] = c;
  for (size_t k = 0; k < h.merges(); ++k) {
    const size_t z = h.leaf_count + k;
    const MergeNode& m = h.nodes[z];
    c += (m.weight * r[z] - h.nodes[m.child[0]].weight * r[m.child[0]] - h.nodes[m.child[1]].weight * r[m.child[1]]) / W;
    after[k + 1] = c;
  }
  CostCurve curve;
  for (size_t k = h.merges() + 1; k-- > 0;) {
    curve.cells.push_back(static_cast<uint32_t>(h.leaf_count - k));
    curve.cost.push_back(after[k]);
  }
  return curve;
}

CostCurve evaluate_subdivision(const Scene& scene, const Subdivision& s,
                               const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model) {
  return subdivision_curve(s, evaluated_bsp_costs(scene, s, leaf_pvs, model));
}

CostCurve evaluate_merge_history(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                 const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model) {
  return merge_history_curve(h, evaluated_merge_costs(scene, s, h, leaf_pvs, model));
}

std::vector<CellCost> subdivision_cells_at(const Subdivision& s, const std::vector<double>& r, uint32_t cells) {
  if (cells < 1 || cells > s.leaf_count()) throw Error("the subdivision has no set of " + std::to_string(cells) + " cells");
  std::vector<CellCost> out;
  for (int32_t n : s.leaves_after(cells - 1)) out.push_back({r[n], s.nodes[n].volume});
  return out;
}

std::vector<CellCost> merged_cells_at(const MergeHistory& h, const std::vector<double>& r, uint32_t cells) {
  if (cells < h.min_cells() || cells > h.leaf_count)
    throw Error("the merge history has no set of " + std::to_string(cells) + " cells");
  std::vector<CellCost> out;
  for (int32_t n : h.cut_after(h.leaf_count - cells)) out.push_back({r[n], h.nodes[n].volume});
  return out;
}

}  // namespace viewcells
