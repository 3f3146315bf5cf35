#pragma once
// The subdivision's builder (view-cell-construction paper, section 4.2): it splits the view
// space cell by cell, each cell by the candidate plane that lowers the expected render cost
// c(S) most. Its parts live in files of their own:
//   subdivision_builder.cpp           the queue driver and its parallel rounds (run)
//   subdivision_nodes.cpp             nodes: their costs, partitions by a plane, splits, evaluation
//   subdivision_axis.cpp              axis-aligned candidates: positions and the sweep of both sides' costs
//   subdivision_geometry.cpp          geometry-aligned candidates (section 4.2.2): planes of hit triangles
//   subdivision_baselines.cpp         the kd-tree and polygon-BSP baselines (section 6)
// Internal to those files and subdivision.cpp.
#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <queue>
#include <utility>
#include <vector>

#include "bsp/subdivision_parts.h"
#include "viewcells/scene/cost_model.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/core/progress.h"
#include "viewcells/scene/scene.h"

namespace viewcells::subdivision_detail {

class Builder {
 public:
  /// Nodes of at least this many parts evaluate their axes (and sort their positions) in
  /// parallel; smaller ones in one thread, their siblings beside them. The same results.
  static constexpr size_t kParallelParts = 1 << 13;
  /// best_axis_candidate in a cell that is not a box: one clip of the cell every kStride positions.
  static constexpr size_t kStride = 16;

  Builder(const Scene& scene, const SegmentSet& segs, const CostModel& model, const SubdivisionConfig& config,
          Subdivision& out)
      : scene_(scene),
        segs_(segs),
        model_(model),
        r_(per_object_costs(scene, model)),
        config_(config),
        out_(out),
        total_volume_(segs.view_box.volume()),
        ends_(segs.size()) {}

  void run();

 private:
  double node_cost(int32_t n) const { return out_.nodes[n].weight / total_weight_ * out_.nodes[n].pvs_cost; }
  double priority(int32_t n) const {
    switch (config_.strategy) {
      case SplitStrategy::kCost: return best_[n].reduction + 0.01 * node_cost(n);
      case SplitStrategy::kKdVisibilityDepthFirst: return n;  // newest first: depth-first
      default: return -static_cast<double>(n);                // oldest first: breadth-first
    }
  }

  double pvs_cost(const ConvexPolyhedron& cell, const RawVector<SegRef>& refs);

  /// A node's parts name their segments in increasing but sparse order, which the hardware does
  /// not predict: the segment a few parts ahead is fetched while this one is used.
  void prefetch_ends(const RawVector<SegRef>& refs, size_t i) const {
    constexpr size_t kAhead = 48;
    if (i + kAhead < refs.size()) __builtin_prefetch(&ends_[refs[i + kAhead].id]);
  }

  /// With the pixel term: calls f(object, r(o) in this cell) once for every object the cell's
  /// segments see (pixels estimated from the cell's bounding box, cost_model.h).
  template <typename F>
  void for_each_cell_cost(const ConvexPolyhedron& cell, const RawVector<SegRef>& refs, F&& f) {
    const std::vector<Vec3> points = pixel_estimation_points(cell.bounds());
    Marks& m = marks_.local();
    m.reset(r_.size());
    for (const SegRef& s : refs)
      for (uint32_t o : {ends_[s.id].object_a, ends_[s.id].object_b})
        if (m.first(o)) f(o, cell_object_cost(scene_.objects[o], r_[o], points, model_));
  }

  /// The object costs candidate splits of `node` are evaluated with: the node's own (pixel
  /// term estimated from the node's points, used for both sides), else the global ones.
  /// Only the entries of objects the node's segments see are written.
  const double* candidate_costs(int32_t node, RawVector<double>& storage);

  /// A node's volume, weight and r(PVS) (thread-safe: the two children are measured at once);
  /// r(PVS) from the node's extents when they are known and the costs are global.
  BspNode measure_node(int32_t parent, const ConvexPolyhedron& cell, const RawVector<SegRef>& refs,
                       const NodeExtents* ext);

  int32_t add_node(int32_t parent, ConvexPolyhedron cell, RawVector<SegRef> refs) {
    const BspNode node = measure_node(parent, cell, refs, nullptr);
    return add_node(node, std::move(cell), std::move(refs));
  }

  int32_t add_node(const BspNode& node, ConvexPolyhedron cell, RawVector<SegRef> refs) {
    const int32_t parent = node.parent;
    depth_.push_back(parent < 0 ? 0 : depth_[parent] + 1);
    plane_hits_.push_back(1);  // until add_children knows better
    out_.nodes.push_back(node);
    out_.cells.push_back(std::move(cell));
    refs_.push_back(std::move(refs));
    return static_cast<int32_t>(out_.nodes.size() - 1);
  }

  /// A node's parts divided by a plane: each child's parts and, for AV-S, extents. It reads
  /// only the node's parts, so it can run beside other work (see run()).
  struct Partition {
    RawVector<SegRef> side[2];
    std::array<NodeExtents, 2> ext;
    bool plane_hits[2] = {false, false};  ///< with geometry-aligned planes: see plane_hits_
  };

  /// AV-S evaluates cells by their extents, which splits gather; the baselines need none.
  bool gathers_extents() const { return config_.strategy == SplitStrategy::kCost; }

  Partition partition(int32_t node, const Plane& plane);

  /// A cell taken from the queue in a round of splits (see run()).
  struct PendingSplit {
    int32_t node = -1;
    Candidate cand;
    int32_t plane_id = -1;  ///< the id of its plane in out_.planes, if it cuts
    std::optional<std::pair<ConvexPolyhedron, ConvexPolyhedron>> halves;
    bool cuts = false;  ///< the plane cuts the cell into two parts, neither a sliver
    Partition parts;
    BspNode measured[2];
    std::vector<uint32_t> tri_side[2];  ///< the polygon BSP baseline: the polygons of each side
    std::vector<uint32_t> point_side[2];  ///< with viewpoints: those of each side
  };

  /// What splitting a cell by its plane gives, without changing any node: its parts divided
  /// and its children measured (and, for the polygon BSP, its polygons divided). Reads only
  /// the node, so the cells of a round are prepared at once.
  void prepare_split(PendingSplit& p);

  /// Adds the two children of a prepared split as the next nodes (ids in the order added).
  void add_children(PendingSplit& p);

  /// Makes a prepared split part of the tree: its plane, and its children (ids c0, c0 + 1).
  void commit_split(const PendingSplit& p, int32_t c0);

  /// Removes the nodes from id n on and the planes of uncommitted splits (the splits undone).
  void truncate_nodes(size_t n);

  /// The queue of cells to split: by priority, ties to the older node.
  using QueueEntry = std::pair<double, int32_t>;  // priority, node
  struct QueueOrder {
    bool operator()(const QueueEntry& x, const QueueEntry& y) const {
      return x.first < y.first || (x.first == y.first && x.second > y.second);  // ties: older node first
    }
  };
  std::priority_queue<QueueEntry, std::vector<QueueEntry>, QueueOrder> queue_;
  double cost_ = 0;         ///< the tree's cost so far
  uint32_t stagnant_ = 0;   ///< successive splits below the minimum reduction
  bool stopped_ = false;    ///< the stagnation rule stopped the splits

  /// The root: planes of the view box, the segments in Z-order, the polygons or viewpoints of
  /// the baselines, the initial cost, and its first evaluation in the queue.
  void start_tree();
  /// The next round: the queue's first cells with their cells cut (run()).
  void take_round(std::vector<PendingSplit>& round, size_t round_size);
  /// A prepared and evaluated round split in the serial order until a child outranks the next
  /// cell (or the stagnation rule stops); the rest undone and queued again. Returns the cells
  /// it went through.
  size_t replay_round(const std::vector<PendingSplit>& round, size_t first_child,
                      const std::vector<Evaluation>& evaluations, Progress& progress);
  /// Each leaf's segment ids in the caller's numbering, and the statistics.
  void finish_tree();

  /// Adds what evaluating a node of the tree took to the statistics (counted once the node is
  /// in the tree: evaluations of a round's undone children are not).
  void count_evaluation(int32_t node, const Evaluation& e);

  Evaluation evaluate(int32_t node);

  /// The kd baselines: the spatial median of the cycling or the longest axis; KD-VT and KD-VT*
  /// leave cells under the PVS budget or at the maximum depth whole.
  Candidate kd_candidate(int32_t node) const;

  /// The BSP baseline: among (a random subset of) the planes of the polygons in the cell, the
  /// one that cuts the fewest polygons and balances the sides best (score 8 * cut + |front -
  /// back|, a classic cell-and-portal heuristic). Sides are counted in floating point here;
  /// the split itself uses exact predicates.
  Candidate best_polygon_candidate(int32_t node, Evaluation& ev);

  /// The axis-aligned positions tried in `node` along each axis (sorted, distinct, strictly
  /// inside the cell's bounds): all segment ends when there are at most max_axis_candidates,
  /// else a random choice, reproducible per node (SubdivisionConfig::exact_candidates).
  ///
  /// The random choice draws parts of the node at random (reproducibly per node) and takes
  /// both ends of each, along every axis that still needs positions, until each has k distinct
  /// ones or 2k parts are drawn (walls, where many segments end, repeat); each part drawn (a
  /// cache miss for its segment) serves the three axes, where drawing an end per axis cost two
  /// dependent misses per position. (A run of consecutive parts from a random one served
  /// until the parts were kept in the Z-order of their segments: a run is now one corner of
  /// the cell.)
  std::array<std::vector<double>, 3> axis_positions(int32_t node, const Box3& bounds) const;

  /// Every segment end of the node along `axis` strictly inside the bounds, sorted and
  /// distinct; a uniform random subset of k of them when there are more (paper, section 4.2).
  std::vector<double> all_axis_positions(int32_t node, int axis, const Box3& bounds) const;

  /// r(PVS) of both sides of the planes at the sorted positions x[0..k-1] along `axis`. A
  /// segment part [lo, hi] is on the negative side at x when lo < x (or it lies in the plane,
  /// lo == hi == x), on the positive side when hi > x (or lies in it): from the first position
  /// index jl on, up to the last index jr. An object is on the negative side from the smallest
  /// jl of its parts on, on the positive side up to the largest jr, which its lowest low end
  /// and highest high end give (NodeExtents); a histogram of those indices and prefix sums give
  /// both sides' costs at every position in O(objects log k + k).
  void side_costs(const NodeExtents& ext, int axis, const std::vector<double>& x, const double* r,
                  std::vector<double>& left, std::vector<double>& right);

  /// The node's parts' extents per object (NodeExtents), in one pass over its parts (in
  /// parallel chunks for large nodes, merged in order, so the result is the same).
  /// The extents of consecutive chunks of parts joined in chunk order (the first moved).
  NodeExtents join_extents(std::vector<NodeExtents>& chunks);

  NodeExtents node_extents(const RawVector<SegRef>& refs);

  /// The best axis-aligned split of `node` along `axis` among its candidate positions.
  Candidate best_axis_candidate(int32_t node, int axis, const std::vector<double>& positions, const NodeExtents& ext,
                                Evaluation& ev, const double* r);

  /// The unit normal of triangle t if its plane is a geometry-aligned candidate (not
  /// degenerate, not axis-aligned).
  std::optional<Vec3> plane_direction(uint32_t t) const;

  /// Whether a node part's end inside the node hit a plane source (the triangles
  /// best_geometry_candidate takes its planes from).
  bool hits_plane_source(const SegRef& s, const SegEnds& e) const;

  /// The best of the planes of non-axis-aligned triangles hit inside the node (a random subset;
  /// each costs O(n)), or none. In a large cell, only the planes whose bound may beat `to_beat`
  /// (the best axis-aligned reduction: ties keep the axis) are evaluated on all parts, so a
  /// plane left out could not have been chosen.
  Candidate best_geometry_candidate(int32_t node, Evaluation& ev, const double* r, double to_beat);

  /// What best_geometry_candidate gathers from a cell's parts in one pass.
  struct GeometryParts {
    struct PartEnds {
      Vec3 p0, p1;
      uint32_t object_a, object_b;
    };
    bool large = false;                    ///< too many parts to keep: bounded by the extremes
    std::vector<PartEnds> parts;           ///< not large: every part's ends and objects, in order
    std::vector<ObjectExtremes> extremes;  ///< large: each object's extreme part ends
    Box3 points;                           ///< every part end
    std::vector<uint32_t> tris;            ///< the distinct triangles hit at ends inside, sorted
  };
  GeometryParts gather_geometry_parts(int32_t node);
  /// One triangle per distinct plane of `tris` (a random subset of at most ga_candidates).
  std::vector<uint32_t> geometry_planes(int32_t node, const std::vector<uint32_t>& tris) const;
  /// r(PVS) of each side of `plane`: exact from the parts, or a lower bound from the extremes.
  std::pair<double, double> geometry_side_costs(int32_t node, const GeometryParts& g, const Plane& plane,
                                                bool from_extremes, const double* r);
  /// Bounded candidates (valid, reduction = bound) evaluated exactly (`exact(j)`) from the
  /// highest bound down until no later one can beat the best; the others made invalid.
  void evaluate_best_bounds(std::vector<Candidate>& results, double to_beat, double margin,
                            const std::function<double(size_t)>& exact);

  const Scene& scene_;
  const SegmentSet& segs_;
  const CostModel& model_;
  const std::vector<double> r_;  ///< max(a, b t_o) per object
  const SubdivisionConfig& config_;
  Subdivision& out_;
  double total_volume_;
  double total_weight_ = 0;
  bool ga_ = false;
  std::vector<RawVector<SegRef>> refs_;
  std::vector<SegEnds> ends_;  ///< per segment, in the builder's order (order_)
  std::vector<size_t> order_;  ///< the builder's segment k is segs_'s order_[k]
  std::vector<uint32_t> depth_;              ///< per node
  /// With geometry-aligned planes: per triangle, whether it is a plane source (plane_direction);
  /// per node, whether one of its parts has an end inside it on a plane source (0: the node
  /// has no geometry-aligned candidates; the root and nodes not made by partition: 1).
  std::vector<uint8_t> plane_source_, plane_hits_;
  std::vector<std::vector<uint32_t>> tris_;  ///< BSP baseline: per node, the polygons in it
  /// With viewpoints (points_): per node, the viewpoints in it (those of split nodes freed),
  /// and the weight of one.
  std::vector<std::vector<uint32_t>> pts_;
  bool points_ = false;
  double point_weight_ = 0;
  double pvs_budget_ = 0;
  uint64_t slivers_refused_ = 0;
  uint64_t splits_undone_ = 0;
  std::vector<Candidate> best_;
  std::atomic<uint64_t> axis_evaluated_{0}, geometry_evaluated_{0}, geometry_full_{0}, parts_evaluated_{0};
  tbb::enumerable_thread_specific<Marks> marks_;
  tbb::enumerable_thread_specific<ExtentSlots> extent_slots_;
  tbb::enumerable_thread_specific<std::array<ExtentSlots, 2>> split_slots_;  ///< apply_split: both sides
  /// Per node: the extents its split gathered, until the node is evaluated.
  std::vector<std::unique_ptr<NodeExtents>> pending_ext_;
  tbb::enumerable_thread_specific<PointMarks> point_marks_;
  tbb::enumerable_thread_specific<std::pair<Marks, Marks>> side_pair_marks_;  ///< geometry-aligned: both sides
  tbb::enumerable_thread_specific<Marks> triangle_marks_;  ///< geometry-aligned: triangles hit in a cell
  tbb::enumerable_thread_specific<std::vector<uint32_t>> extreme_entry_;  ///< geometry-aligned: see extremes
  mutable tbb::enumerable_thread_specific<std::array<DrawnSet, 3>> drawn_;
};

}  // namespace viewcells::subdivision_detail
