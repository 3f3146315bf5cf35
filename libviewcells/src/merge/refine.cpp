// Boundary refinement of blocks of a partition (merge/merge.h: refine_blocks).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "viewcells/core/error.h"
#include "viewcells/merge/merge.h"

namespace viewcells {

namespace {

/// The state of a refinement: the units (dense ids, weights, PVSs as unions of their cells',
/// neighbours), the block of each, and per block its weight W, the cost R of its PVS (object
/// counts kept per block) and its number of units. The partition's cost is the sum of W * R.
class Refiner {
 public:
  Refiner(const CellPartition& partition, std::vector<double> r, const std::vector<int32_t>& unit,
          const std::vector<int32_t>& block)
      : r_(std::move(r)), n_(partition.size()), objects_(r_.size()) {
    make_units(partition, unit);
    make_blocks(block);
  }

  double total() const { return total_; }

  /// One pass over the units, each moved to the neighbouring block that lowers the cost most
  /// (its block staying connected without it); returns how many moved.
  uint64_t pass() {
    uint64_t moved = 0;
    for (size_t xi = 0; xi < u_; ++xi) {
      const auto x = static_cast<int32_t>(xi);
      int32_t to = -1;
      const double best = best_move(x, to);
      // Gains below rounding of the total are not moves (no cycling on ties).
      if (to < 0 || !(best > 1e-12 * total_) || !connected_without(x, of_[x])) continue;
      move(x, to, best);
      ++moved;
    }
    return moved;
  }

  /// Each partition cell's block label.
  std::vector<int32_t> labels() const {
    std::vector<int32_t> out(n_);
    for (size_t c = 0; c < n_; ++c) out[c] = bnames_[static_cast<size_t>(of_[id_[c]])];
    return out;
  }

 private:
  /// Units: dense ids, their weights, PVSs (unions of their cells') and neighbours.
  void make_units(const CellPartition& partition, const std::vector<int32_t>& unit) {
    id_.resize(n_);
    names_ = unit;
    std::sort(names_.begin(), names_.end());
    names_.erase(std::unique(names_.begin(), names_.end()), names_.end());
    for (size_t c = 0; c < n_; ++c)
      id_[c] = static_cast<int32_t>(std::lower_bound(names_.begin(), names_.end(), unit[c]) - names_.begin());
    u_ = names_.size();
    w_.assign(u_, 0.0);
    // Each unit's PVS, the union of its cells': cells grouped by unit, objects deduplicated by
    // a stamp per object (linear in the cells' entries; only the unions are sorted).
    std::vector<uint32_t> first(u_ + 1, 0), cells_by_unit(n_);
    for (size_t c = 0; c < n_; ++c) ++first[id_[c] + 1];
    for (size_t x = 0; x < u_; ++x) first[x + 1] += first[x];
    {
      std::vector<uint32_t> at(first.begin(), first.end() - 1);
      for (size_t c = 0; c < n_; ++c) cells_by_unit[at[id_[c]]++] = static_cast<uint32_t>(c);
    }
    pvs_.assign(u_, {});
    std::vector<uint32_t> stamp(objects_, UINT32_MAX);
    for (size_t x = 0; x < u_; ++x) {
      auto& l = pvs_[x];
      for (uint32_t i = first[x]; i < first[x + 1]; ++i) {
        const uint32_t c = cells_by_unit[i];
        w_[x] += partition.weight[c];
        for (uint32_t o : partition.pvs[c])
          if (stamp[o] != x) {
            stamp[o] = static_cast<uint32_t>(x);
            l.push_back(o);
          }
      }
      std::sort(l.begin(), l.end());
    }
    next_.assign(u_, {});
    for (const auto& [a, b] : partition.neighbours) {
      const int32_t x = id_[a], y = id_[b];
      if (x != y) {
        next_[x].push_back(y);
        next_[y].push_back(x);
      }
    }
    for (auto& l : next_) {
      std::sort(l.begin(), l.end());
      l.erase(std::unique(l.begin(), l.end()), l.end());
    }
    seen_.assign(u_, 0);
  }

  /// Blocks: each unit's (every cell of a unit must share it), dense ids; their W, R, sizes.
  void make_blocks(const std::vector<int32_t>& block) {
    of_.assign(u_, -1);
    for (size_t c = 0; c < n_; ++c) {
      if (of_[id_[c]] >= 0 && of_[id_[c]] != block[c]) throw Error("refine_blocks: a unit lies in two blocks");
      of_[id_[c]] = block[c];
    }
    bnames_ = of_;
    std::sort(bnames_.begin(), bnames_.end());
    bnames_.erase(std::unique(bnames_.begin(), bnames_.end()), bnames_.end());
    const size_t k = bnames_.size();
    for (int32_t& b : of_)
      b = static_cast<int32_t>(std::lower_bound(bnames_.begin(), bnames_.end(), b) - bnames_.begin());
    count_.assign(k * objects_, 0);
    W_.assign(k, 0.0);
    R_.assign(k, 0.0);
    size_.assign(k, 0);
    for (size_t x = 0; x < u_; ++x) {
      const size_t b = static_cast<size_t>(of_[x]);
      W_[b] += w_[x];
      ++size_[b];
      for (uint32_t o : pvs_[x])
        if (count_[b * objects_ + o]++ == 0) R_[b] += r_[o];
    }
    total_ = 0;
    for (size_t b = 0; b < k; ++b) total_ += W_[b] * R_[b];
  }

  uint32_t& count(int32_t block, uint32_t object) { return count_[static_cast<size_t>(block) * objects_ + object]; }

  /// The largest gain of moving unit x to a neighbouring block (0 and `to` -1 when none gains).
  double best_move(int32_t x, int32_t& to) {
    const int32_t a = of_[x];
    if (size_[a] <= 1) return 0;
    targets_.clear();
    for (int32_t y : next_[x])
      if (of_[y] != a) targets_.push_back(of_[y]);
    if (targets_.empty()) return 0;
    std::sort(targets_.begin(), targets_.end());
    targets_.erase(std::unique(targets_.begin(), targets_.end()), targets_.end());
    double drop = 0;
    for (uint32_t o : pvs_[x])
      if (count(a, o) == 1) drop += r_[o];
    const double after_a = (W_[a] - w_[x]) * (R_[a] - drop), before_a = W_[a] * R_[a];
    double best = 0;
    for (int32_t b : targets_) {
      double add = 0;
      for (uint32_t o : pvs_[x])
        if (count(b, o) == 0) add += r_[o];
      const double gain = before_a + W_[b] * R_[b] - after_a - (W_[b] + w_[x]) * (R_[b] + add);
      if (gain > best) {
        best = gain;
        to = b;
      }
    }
    return best;
  }

  void move(int32_t x, int32_t to, double gain) {
    const int32_t a = of_[x];
    for (uint32_t o : pvs_[x]) {
      if (--count(a, o) == 0) R_[a] -= r_[o];
      if (count(to, o)++ == 0) R_[to] += r_[o];
    }
    W_[a] -= w_[x];
    W_[to] += w_[x];
    --size_[a];
    ++size_[to];
    of_[x] = to;
    total_ -= gain;
  }

  /// Whether block b stays connected without unit x (b has more than one unit).
  bool connected_without(int32_t x, int32_t b) {
    ++epoch_;
    int32_t start = -1;
    for (int32_t y : next_[x])
      if (of_[y] == b) {
        start = y;
        break;
      }
    if (start < 0) return false;
    seen_[x] = epoch_;
    seen_[start] = epoch_;
    stack_.assign(1, start);
    uint32_t reached = 1;
    while (!stack_.empty()) {
      const int32_t y = stack_.back();
      stack_.pop_back();
      for (int32_t z : next_[y])
        if (of_[z] == b && seen_[z] != epoch_) {
          seen_[z] = epoch_;
          ++reached;
          stack_.push_back(z);
        }
    }
    return reached == size_[b] - 1;
  }

  const std::vector<double> r_;  // per object
  const size_t n_, objects_;
  size_t u_ = 0;
  std::vector<int32_t> id_, names_;             // per cell its unit; per unit its label
  std::vector<double> w_;                       // per unit
  std::vector<std::vector<uint32_t>> pvs_;      // per unit
  std::vector<std::vector<int32_t>> next_;      // per unit: neighbouring units
  std::vector<int32_t> of_, bnames_;            // per unit its block; per block its label
  std::vector<uint32_t> count_;                 // per block and object: units seeing it
  std::vector<double> W_, R_;                   // per block
  std::vector<uint32_t> size_;                  // per block: units
  double total_ = 0;
  std::vector<uint32_t> seen_;                  // connected_without's scratch
  uint32_t epoch_ = 0;
  std::vector<int32_t> stack_, targets_;
};

}  // namespace

std::vector<int32_t> refine_blocks(const Scene& scene, const CellPartition& partition, const CostModel& model,
                                   const std::vector<int32_t>& unit, const std::vector<int32_t>& block,
                                   uint32_t max_passes, RefineStats* stats) {
  if (unit.size() != partition.size()) throw Error("refine_blocks: one unit per partition cell");
  if (model.pixel_term()) throw Error("refine_blocks: the pixel term is not supported");
  Refiner refiner(partition, per_object_costs(scene, model), unit, block);
  const double initial = refiner.total();
  uint32_t passes = 0;
  uint64_t moves = 0;
  for (; passes < max_passes; ++passes) {
    const uint64_t moved = refiner.pass();
    moves += moved;
    if (!moved) break;
  }
  if (stats) {
    stats->passes = passes;
    stats->moves = moves;
    stats->cost_before = initial;
    stats->cost_after = refiner.total();
  }
  return refiner.labels();
}

}  // namespace viewcells
