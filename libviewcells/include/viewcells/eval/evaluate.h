#pragma once
/// The evaluator (view-cell-construction paper, section 6.1): independent evaluation samples
/// give every cell of a hierarchy a PVS, and c(S) is read off at every cell count along the
/// method's own refinement order: the split order of a BSP or kd-tree (AV-S and the
/// baselines), the merge history backwards (AV-M). Construction never sees these samples.
#include <cstdint>
#include <memory>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/merge/merge.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// Per node of `s` (filled for leaves): the sorted objects seen by the segments of `eval`
/// that have length in the leaf. Parallel; the result does not depend on the thread count.
std::vector<std::vector<uint32_t>> evaluation_pvs(const Subdivision& s, const SegmentSet& eval);
/// How evaluation_pvs gathers each leaf's objects; the lists are the same either way.
/// kLists: per thread, lists that grow as segments meet the leaf, then sorted, made unique and
/// joined. kBits: one bit per leaf and object, shared by the threads (a bit is set atomically
/// where it is not set yet; stored per object over the leaves, so that the leaves a segment
/// crosses in turn share cache lines), read out in order at the end: no lists to grow, sort or
/// join. kAutomatic: bits where the scene has at least 512 objects and the bits take at most
/// 512 MB (and, for one call of
/// evaluation_pvs, at most 64 bytes per segment walked, so that a few segments do not clear and
/// read rows for every leaf), else lists.
enum class LeafGather { kAutomatic, kLists, kBits };

/// The same, walking the segments in `order` (a permutation of their indices; the result does
/// not depend on it, the time does: coherent_order(eval, ...), computed once for many trees).
std::vector<std::vector<uint32_t>> evaluation_pvs(const Subdivision& s, const SegmentSet& eval,
                                                  const std::vector<size_t>& order,
                                                  LeafGather gather = LeafGather::kAutomatic);

/// The evaluation PVSs of a subdivision's leaves from segments added a set at a time (as they
/// are drawn, so that they are never all held): the same lists as evaluation_pvs on all of them
/// at once. With bits (LeafGather) each set only
/// sets bits, and the lists are read out once; else each set's lists are united with the ones
/// before.
class EvaluationPvs {
 public:
  /// `objects`: more than any object id the segments see (Scene::objects.size()).
  EvaluationPvs(const Subdivision& s, size_t objects, LeafGather gather = LeafGather::kAutomatic);
  ~EvaluationPvs();
  EvaluationPvs(EvaluationPvs&&) noexcept;
  /// Walks `eval` in `order` (a permutation of its indices), or in coherent_order.
  void add(const SegmentSet& eval, const std::vector<size_t>& order);
  void add(const SegmentSet& eval);
  /// Per node of the subdivision (filled for leaves), from every set added so far.
  std::vector<std::vector<uint32_t>> lists() const;
  /// The same, moved out (no copy of the lists): it is then empty, as if nothing had been added.
  std::vector<std::vector<uint32_t>> take();
  bool bits() const;  ///< whether it gathers by bits

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};


/// c(S) against the number of cells.
struct CostCurve {
  std::vector<uint32_t> cells;  ///< increasing
  std::vector<double> cost;
  /// The cost at `n` cells (Error if the curve has no such point).
  double at(uint32_t n) const;
};

/// Evaluated r(PVS) of every node of the BSP `s` (inner nodes: the union of their leaves),
/// from the leaves' evaluation PVSs; what the curves and cell sets below read.
std::vector<double> evaluated_bsp_costs(const Scene& scene, const Subdivision& s,
                                        const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model);
/// The same for every node of the merge history `h` over the leaves of `s`.
std::vector<double> evaluated_merge_costs(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                          const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model);

/// A merge history's evaluation replay kept at some of its cuts, so that the evaluation of
/// another history over the same leaves and leaf PVSs that begins with the same merges starts
/// at the latest such cut instead of at the leaves (the validated merge scores dozens of
/// candidate histories, most beginning with many of AV-S's own merges). Only where
/// evaluated_merge_costs works on bit sets (whole object costs, no pixel term, bit sets no
/// larger than the lists); elsewhere it holds nothing and changes nothing.
struct MergeReplayCuts {
  struct Cut {
    size_t merges = 0;            ///< merges done at this cut
    std::vector<int32_t> live;    ///< its cells (history nodes)
    std::vector<uint64_t> bits;   ///< their PVSs as bit sets over the objects, live.size() x words
  };
  const MergeHistory* history = nullptr;  ///< the history replayed (must outlive this)
  const std::vector<std::vector<uint32_t>>* leaf_pvs = nullptr;  ///< on these (must outlive this)
  std::vector<double> r;                  ///< r(PVS) of every node of `history`
  size_t words = 0;
  std::vector<Cut> cuts;  ///< increasing merges
};
/// Replays `h` (as evaluated_merge_costs does) and keeps its cuts after each of `merges`.
MergeReplayCuts replay_merge_cuts(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                  const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model,
                                  std::vector<size_t> merges);
/// evaluated_merge_costs of `h`, starting from the latest cut of `from` whose merges `h` begins
/// with (compared node by node; none unless `leaf_pvs` is the very object `from` replayed):
/// the same values, exactly, as without `from`.
std::vector<double> evaluated_merge_costs(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                          const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model,
                                          const MergeReplayCuts& from);

/// c(S) after every split of `s`, 1 .. leaf_count cells, from evaluated_bsp_costs.
CostCurve subdivision_curve(const Subdivision& s, const std::vector<double>& node_cost);
/// c(S) along the merge history, min_cells .. leaf_count cells, from evaluated_merge_costs.
CostCurve merge_history_curve(const MergeHistory& h, const std::vector<double>& node_cost);

/// Both in one call, for a single curve.
CostCurve evaluate_subdivision(const Scene& scene, const Subdivision& s,
                               const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model);
CostCurve evaluate_merge_history(const Scene& scene, const Subdivision& s, const MergeHistory& h,
                                 const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model);

/// One view cell of a set, for render cost histograms over the view space volume.
struct CellCost {
  double cost = 0;    ///< evaluated r(PVS)
  double volume = 0;
};
/// The cells of `s` after `cells - 1` splits.
std::vector<CellCost> subdivision_cells_at(const Subdivision& s, const std::vector<double>& node_cost, uint32_t cells);
/// The cells of the merge history's cut with `cells` cells.
std::vector<CellCost> merged_cells_at(const MergeHistory& h, const std::vector<double>& node_cost, uint32_t cells);

}  // namespace viewcells
