#pragma once
/// View space merging and the merge history tree (view-cell-construction paper, section 4.3),
/// and view cell extraction from it (section 5.1).
///
/// Merging is greedy: always merge the pair of neighbouring cells whose merge raises the
/// expected render cost c(S) the least, delta(x, y) = c({x + y}) - c({x, y}). Each merge is a
/// node of the merge history tree (MHT): nodes 0 .. L-1 are the elementary cells, node L + k
/// is merge k, and cutting the tree after k merges gives the L - k cells the greedy found.
/// It works on any partition of the view space into cells with PVSs and a neighbour relation:
/// the leaves of our AV-S subdivision, or a kD-tree's cells.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/core/vec3.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// A partition of the view space, the input of merging.
struct CellPartition {
  std::vector<double> weight;                   ///< per cell: integral of the viewpoint density
  std::vector<double> volume;                   ///< per cell
  std::vector<Box3> bounds;                     ///< per cell (the pixel term's points)
  std::vector<std::vector<uint32_t>> pvs;       ///< per cell: sorted object ids
  std::vector<std::pair<uint32_t, uint32_t>> neighbours;  ///< cells sharing a face, first < second

  size_t size() const { return weight.size(); }
};

/// The leaves of `s` as a partition, in the order of s.leaves(); `leaf_pvs` is per node
/// (bsp/subdivision.h: leaf_pvs). Needs the leaf cells (s.cells) for the neighbours.
CellPartition partition_from_subdivision(const Subdivision& s, const std::vector<std::vector<uint32_t>>& leaf_pvs);
/// The same, the leaves' lists moved into the partition rather than copied.
CellPartition partition_from_subdivision(const Subdivision& s, std::vector<std::vector<uint32_t>>&& leaf_pvs);

/// A uniform nx x ny x nz grid over segments.view_box as a partition (the simplest kD
/// partition: a baseline, and a test that merging takes any partition). A cell's PVS is the
/// objects of the segments with positive length inside it; neighbours share a face.
CellPartition grid_partition(const SegmentSet& segments, int nx, int ny, int nz);

struct MergeNode {
  int32_t child[2] = {-1, -1};  ///< -1 for an elementary cell
  int32_t parent = -1;          ///< -1 for a root
  double weight = 0, volume = 0;
  Box3 bounds;
  double pvs_cost = 0;     ///< r(PVS) of the (merged) cell
  uint32_t pvs_size = 0;   ///< objects in its PVS
};

struct MergeStats {
  uint64_t evaluations = 0;  ///< delta(x, y) computed
  uint64_t stale = 0;        ///< queue entries skipped because a side had merged already
  double seconds = 0;
};

struct MergeHistory {
  uint32_t leaf_count = 0;
  std::vector<MergeNode> nodes;  ///< leaves first, then one per merge
  /// c(S) after each merge: cost_after[k] holds for leaf_count - k - 1 cells.
  std::vector<double> cost_after;
  double initial_cost = 0;       ///< c(S) of the elementary cells
  double total_weight = 0;
  MergeStats stats;

  size_t merges() const { return nodes.size() - leaf_count; }
  /// Smallest number of cells the merges reach (1 unless the neighbour graph is disconnected).
  size_t min_cells() const { return leaf_count - merges(); }
  /// c(S) with `cells` cells (min_cells() <= cells <= leaf_count).
  double cost_with(size_t cells) const;
  /// The cells (MHT node ids) after the first k merges, sorted.
  std::vector<int32_t> cut_after(size_t k) const;
  /// The elementary cells (leaf ids) under node n, sorted.
  std::vector<uint32_t> leaves_under(int32_t n) const;
};

struct MergeConfig {
  uint32_t min_cells = 1;  ///< stop merging at this many cells
  /// Merges done first, in order, before the greedy ones: pairs of current MHT node ids (a
  /// prefix merge j creates node leaf_count + j). E.g. subdivision_prefix: the subdivision's
  /// own order back to a coarser cut, from which the greedy merging continues.
  std::vector<std::pair<int32_t, int32_t>> prefix;
  /// A barrier: while more than `barrier_cells` cells remain, greedy merges join only cells
  /// of the same block (`block`, per partition cell; empty: no barrier). With blocks that are
  /// the subdivision's cut at barrier_cells cells (subdivision_blocks), the cut of the history
  /// at that count is exactly the subdivision's, and greedy merging goes on from there.
  uint32_t barrier_cells = 0;
  std::vector<int32_t> block;
  bool show_progress = true;
};

/// Merges greedily down to config.min_cells cells (or as far as the neighbour graph allows).
/// Deterministic: ties go to the pair with the smaller node ids.
MergeHistory merge_cells(const Scene& scene, const CellPartition& partition, const CostModel& model,
                         const MergeConfig& config = {});

/// merge_cells for each of `configs`, in parallel, with the same histories as merge_cells gives
/// each: configs whose prefixes are the first merges of one longest prefix (subdivision_prefix
/// at several counts, say) share its merges, which are done once; at each config's end of it,
/// a copy of that state merges on greedily as the config says. `done(i, history)` receives
/// configs[i]'s history as soon as it is ready, on any thread. Throws if a prefix is not the
/// first merges of the longest.
void merge_cells_sharing_prefix(const Scene& scene, const CellPartition& partition, const CostModel& model,
                                const std::vector<MergeConfig>& configs,
                                const std::function<void(size_t, MergeHistory)>& done);

/// The subdivision's splits undone, the last first, down to `cells` cells, as merges of the
/// partition_from_subdivision(s, ...) cells (MergeConfig::prefix): its cuts are then exactly
/// the subdivision's own (AV-S's) cuts from leaf_count() down to `cells`.
std::vector<std::pair<int32_t, int32_t>> subdivision_prefix(const Subdivision& s, size_t cells);

/// Per partition_from_subdivision(s, ...) cell: the node of the subdivision's own cut at
/// `cells` cells that holds it (MergeConfig::block).
std::vector<int32_t> subdivision_blocks(const Subdivision& s, size_t cells);

/// What refine_blocks did: passes over the units, units moved, and the blocks' c(S) (sum of
/// weight x r(PVS), not normalised) before and after.
struct RefineStats {
  uint32_t passes = 0;
  uint64_t moves = 0;
  double cost_before = 0, cost_after = 0;
};

/// Boundary refinement of a partition's blocks (a greedy Kernighan-Lin pass, as multilevel
/// graph partitioners refine their coarsened cuts). The partition's cells are grouped into
/// units (`unit`, a label per cell), and the units into blocks (`block`, a label per cell,
/// the same for every cell of a unit). A unit moves to a neighbouring block while that lowers
/// the blocks' sum of weight x r(PVS) (the PVS of a block: the union of its cells'), and
/// only when its own block stays connected and not empty; passes over the units in order
/// until none moves or `max_passes`. Deterministic. Returns the refined block per cell (the
/// same labels). Not with the pixel term (Error).
std::vector<int32_t> refine_blocks(const Scene& scene, const CellPartition& partition, const CostModel& model,
                                   const std::vector<int32_t>& unit, const std::vector<int32_t>& block,
                                   uint32_t max_passes = 20, RefineStats* stats = nullptr);

/// Every merge of `h`, in order, each cell named by the least leaf under it. A cell of a cut
/// is a set of leaves, so these names hold across histories whose cuts agree: merges of one
/// history down to a count where its cut equals another's, followed by the other's merges
/// from there, form one history.
std::vector<std::pair<int32_t, int32_t>> merges_by_least_leaf(const MergeHistory& h);
/// Merges named by least leaf (each naming two current cells) as MergeConfig::prefix node ids.
std::vector<std::pair<int32_t, int32_t>> least_leaf_merges_as_prefix(
    const std::vector<std::pair<int32_t, int32_t>>& merges, size_t leaves);

/// A set of view cells cut from the merge history.
struct ViewCellSet {
  std::vector<int32_t> cells;  ///< MHT node ids, sorted
  double cost = 0;             ///< c(S) of the set
  uint64_t pvs_entries = 0;    ///< sum of the cells' PVS sizes
  uint64_t pvs_bytes = 0;      ///< approx_pvs_bytes of the set
  std::string rule;            ///< how it was chosen, in words
};

/// Approximate PVS storage of a cell: a 32-bit id per object plus a 4-byte count.
inline uint64_t approx_pvs_bytes(uint32_t pvs_size) { return 4ull * pvs_size + 4; }

/// Exactly `count` cells (min_cells() <= count <= leaf_count, else Error).
ViewCellSet extract_by_count(const MergeHistory& h, size_t count);
/// The most cells whose approximate PVS storage fits in `bytes`, walking the history back
/// from its coarsest cut (paper 5.1: stop when the budget is reached). Error if not even the
/// coarsest cut fits.
ViewCellSet extract_by_memory(const MergeHistory& h, uint64_t bytes);
/// The fewest cells whose cost is at most `ratio` times the cost of the elementary cells
/// (ratio >= 1).
ViewCellSet extract_by_cost_ratio(const MergeHistory& h, double ratio);

}  // namespace viewcells
