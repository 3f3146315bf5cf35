#pragma once
/// Adaptive view space subdivision, AV-S (view-cell-construction paper, section 4.2): a BSP of
/// the view space refined greedily, always splitting the leaf whose best plane reduces the
/// expected render cost c(S) the most (priority: reduction + 1% of the leaf's own cost).
/// Axis-aligned candidates lie at the clipped segment endpoints; both sides' r(PVS) at all k
/// positions of an axis come from each object's lowest and highest extent in the node, which
/// the pass that divides its parent's parts gathers (then a binary search per object and prefix
/// sums: O(n + objects log k) per node); geometry-aligned candidates are planes of scene
/// triangles hit inside the node, a random subset of at most ga_candidates. Splits go in rounds:
/// the first cells of the queue are divided and their children evaluated in parallel, then the
/// serial order is replayed (a cell that a new child outranks goes back to the queue).
/// Deterministic: the same inputs and seed give the same tree for any number of threads.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/plane.h"
#include "viewcells/bsp/polyhedron.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

enum class GeometryAlignedMode { kAuto, kOn, kOff };

/// Optional viewpoint density (paper, section 3.3): weight 1 for viewpoints whose height lies
/// in [lo, hi] (where players walk, say), `outside` (>= 0) elsewhere. Then
/// p(i) = integral of the density over cell i / integral over the view space.
struct HeightBandDensity {
  bool enabled = false;
  double lo = 0, hi = 0;
  double outside = 0.1;
  /// Integral of the density over a convex cell (its volume when disabled).
  double weight(const ConvexPolyhedron& cell) const;
  /// Integral of the density over the negative side of `plane` within `cell`; `band_part` is
  /// the cell clipped to the band (see band_part()).
  double weight_below(const ConvexPolyhedron& cell, const ConvexPolyhedron& band_part, const Plane& plane) const;
  /// The part of `cell` with lo <= z <= hi (empty if none).
  ConvexPolyhedron band_part(const ConvexPolyhedron& cell) const;
};

/// How cells are chosen and split. kCost is AV-S; the others are the baselines of the
/// paper's section 6.3, built in the same BSP so that one evaluator compares them all.
enum class SplitStrategy {
  kCost,       ///< AV-S: the split that lowers c(S) the most, best cell first (paper 4.2)
  kKdCycling,  ///< KD-CASM: breadth-first kd-tree, spatial median, axes x, y, z in turn
  kKdLongest,  ///< KD-LASM: breadth-first kd-tree, spatial median of the longest axis
  /// KD-VT: KD-LASM, but a cell whose sampled r(PVS) is at most the PVS budget, or at the
  /// maximum depth, is not split.
  kKdVisibility,
  kKdVisibilityDepthFirst,  ///< KD-VT*: KD-VT depth-first (Saona-Vazquez et al., Nirenstein et al.)
  /// BSP: planes of the scene's polygons inside the cell only, chosen as cell-and-portal
  /// builders do (few polygons cut, balanced sides), breadth-first; a cell without polygons
  /// is not split (empty space stays whole).
  kPolygonBsp,
};
/// "av-s", "kd-casm", "kd-lasm", "kd-vt", "kd-vt-star", "bsp" (Error otherwise).
SplitStrategy parse_split_strategy(const std::string& name);
const char* to_string(SplitStrategy s);

struct SubdivisionConfig {
  SplitStrategy strategy = SplitStrategy::kCost;
  /// KD-VT, KD-VT*: cells whose sampled r(PVS) is at most this share of the whole view
  /// space's r(PVS) are not split.
  double pvs_budget_share = 0.05;
  uint32_t max_depth = 40;           ///< KD-VT, KD-VT*: deepest level split
  uint32_t polygon_candidates = 50;  ///< BSP: polygon planes tried per cell at most
  uint32_t max_cells = 1000;           ///< stop at this many leaves
  uint32_t max_axis_candidates = 200;  ///< positions per axis (a random subset of segment ends beyond)
  /// How the axis-aligned positions of a cell are drawn when it has more segment ends than
  /// max_axis_candidates. Exact (the paper's): a uniform random subset of the distinct end
  /// coordinates, which needs them all sorted (O(n log n) per cell and axis). Fast (the
  /// default, once a cell has more than 4 x max_axis_candidates ends): the ends of parts of the
  /// cell drawn at random, until max_axis_candidates distinct ones per axis (or 2 x as many
  /// parts drawn), so coordinates where many segments end (walls) are likelier: O(k log k).
  /// Either way every chosen position is evaluated exactly.
  bool exact_candidates = false;
  /// In a cell that is not a box, an axis position's volume below is a clip of the cell; the
  /// builder clips only where the volume can change the choice. True: at every position, for
  /// tests that check it is the same choice.
  bool clip_every_position = false;
  GeometryAlignedMode geometry_aligned = GeometryAlignedMode::kAuto;
  uint32_t ga_candidates = 150;       ///< geometry-aligned planes per node at most (paper: 150)
  /// kAuto enables geometry-aligned candidates when at least this share of the surface area
  /// is not axis-aligned.
  double ga_auto_share = 0.05;
  /// Stop when the best reduction stayed below min_reduction * (cost of the whole view space)
  /// for stagnation_steps successive splits.
  double min_reduction = 1e-6;
  uint32_t stagnation_steps = 50;
  uint64_t seed = 1;
  /// Cells divided, and their children evaluated, at once (see subdivide()); at least 1. The
  /// tree does not depend on it: 1 is the serial loop, one split at a time.
  uint32_t split_round = 16;
  bool show_progress = true;
  HeightBandDensity density;  ///< uniform (p(i) = V_i / V) unless enabled
  /// A viewpoint density given by points of equal weight (on a map: player eyes): a cell
  /// weighs the share of them in it times the view box's volume (a point on a splitting plane
  /// counts on its negative side, as Subdivision::locate puts it), so that a cell without
  /// any weighs nothing and gains nothing from being divided. Not with `density`. Null: the
  /// density above.
  std::shared_ptr<const std::vector<Vec3>> viewpoints;
  /// On a Quake 3 map: the pipeline draws `viewpoints` as player eyes (q3/play.h), so p(i) is
  /// where players are rather than all non-solid space.
  bool play_space = false;
};

struct BspNode {
  int32_t plane = -1;            ///< split plane (index into planes); -1 for a leaf
  int32_t child[2] = {-1, -1};   ///< negative side, positive side
  int32_t parent = -1;
  double volume = 0;
  double weight = 0;             ///< integral of the viewpoint density (= volume when uniform)
  double pvs_cost = 0;           ///< r(PVS) from the segments in the node
};

/// One split, in the order it happened: replaying the first k gives the subdivision with
/// k + 1 cells exactly. Split k creates nodes 2k + 1 (negative side) and 2k + 2.
struct SplitRecord {
  int32_t node = -1;
  double reduction = 0;   ///< c(S) before minus after
  double cost_after = 0;  ///< c(S) after this split
};

struct SubdivisionStats {
  uint64_t axis_candidates = 0;      ///< candidate planes evaluated, by kind
  uint64_t geometry_candidates = 0;
  /// Geometry-aligned candidates evaluated on all of their cell's parts (the others were
  /// bounded from their objects' extreme part ends below a candidate that beats them).
  uint64_t geometry_full_passes = 0;
  /// Segment parts read by candidate evaluation, summed over the cells evaluated (a segment
  /// lies in every cell it crosses, so this grows faster than the segments).
  uint64_t parts_evaluated = 0;
  uint64_t slivers_refused = 0;      ///< chosen splits left undone: a part would be a sliver
  /// Cells taken in a round of splits and put back, because a child split off before them in
  /// the round outranked them (their division and their children's evaluation were redone).
  uint64_t splits_undone = 0;
  bool geometry_aligned = false;
  std::string geometry_aligned_reason;
  std::string stop_reason;
  double seconds = 0;
};

struct Subdivision {
  Box3 view_box;
  std::vector<Plane> planes;  ///< 0..5: the view box faces; then one per split
  std::vector<BspNode> nodes;
  std::vector<SplitRecord> splits;
  std::vector<ConvexPolyhedron> cells;          ///< per node; filled for leaves only
  /// Per node: ids of the segments it holds (leaves), in the subdivision's own order (that of
  /// coherent_order, not sorted).
  std::vector<std::vector<uint32_t>> segments;
  double initial_cost = 0;                      ///< c(S) of the single cell
  SubdivisionStats stats;

  size_t leaf_count() const { return splits.size() + 1; }
  std::vector<int32_t> leaves() const;
  /// c(S) of the current leaves: sum of p(i) r(PVS_i), p(i) = weight_i / weight of the root.
  double cost() const;
  /// The leaf containing p (points on a plane go to its negative side); -1 outside the box.
  int32_t locate(const Vec3& p) const;
  /// The leaves of the subdivision after its first k splits (k <= splits.size()).
  std::vector<int32_t> leaves_after(size_t k) const;
  /// The leaves the segment a-b (inside the view box) has length in, by the same rule the
  /// subdivision distributes its own segments with; appended to `out`, `stack` is scratch.
  void leaves_of_segment(const Vec3& a, const Vec3& b, std::vector<int32_t>& out,
                         std::vector<std::tuple<int32_t, double, double>>& stack) const;
  /// The same, with the part of the segment in each leaf: (leaf, t0, t1) for the points
  /// a + t (b - a), t in [t0, t1].
  void pieces_of_segment(const Vec3& a, const Vec3& b, std::vector<std::tuple<int32_t, double, double>>& out,
                         std::vector<std::tuple<int32_t, double, double>>& stack) const;
};

/// Pushes `cell` down the tree of `s` from its root (convex clipping at every node it
/// straddles), calling at_leaf(leaf, part) for every leaf it has volume in. Works on any
/// tree of Subdivision nodes, in any node order.
void clip_to_leaves(const Subdivision& s, const ConvexPolyhedron& cell,
                    const std::function<void(int32_t, const ConvexPolyhedron&)>& at_leaf);

/// Decides whether geometry-aligned candidates are used, and why.
bool use_geometry_aligned(const Scene& scene, const SubdivisionConfig& config, std::string& reason);

/// Builds AV-S over segments.view_box under the render-cost model `model`. With its pixel
/// term (c > 0) every cell has its own object costs (cost_model.h); candidate planes of a cell
/// are then evaluated with the cell's costs on both sides, and the split's recorded cost uses
/// each child's own, so a split can then raise c(S) a little where an estimate was off.
Subdivision subdivide(const Scene& scene, const SegmentSet& segments, const CostModel& model,
                      const SubdivisionConfig& config);

/// Sorted object ids seen by the segments of each leaf of `s` (per node; empty for inner nodes).
std::vector<std::vector<uint32_t>> leaf_pvs(const Subdivision& s, const SegmentSet& segments);

/// Recomputes the leaf polyhedra (s.cells) by replaying the splits from the view box (a
/// subdivision read from disk keeps only its tree).
void rebuild_cells(Subdivision& s);

}  // namespace viewcells
