/// A Quake 3 map's view spaces (q3/map_view_space.h): its non-solid space, and the play space
/// within it (paper section 3.3: the view space and the viewpoint density p(i)).
#include "viewcells/q3/map_view_space.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <utility>

#include "viewcells/core/error.h"
#include "viewcells/core/rng.h"
#include "viewcells/q3/play.h"
#include "viewcells/q3/view_space.h"

namespace viewcells {

namespace {

/// Points drawn in the play space as the subdivision's viewpoint density.
constexpr uint32_t kPlayViewpoints = 200000;

/// `count` points uniform in the leaves of `q3` (a q3_subdivision) that weigh something, by
/// volume: a leaf drawn by weight, a point of its bounds until it lies in the leaf (after 1,000
/// misses, a leaf that fills under 0.1% of its bounds, the bounds' centre stands for it).
std::vector<Vec3> uniform_points(const Subdivision& q3, const Q3Map& map, uint32_t count, uint64_t seed) {
  const int32_t inner = static_cast<int32_t>(map.nodes.size());
  std::vector<std::pair<double, int32_t>> by_weight;  // (weight so far, leaf)
  double total = 0;
  for (int32_t l = 0; l < static_cast<int32_t>(map.leaves.size()); ++l)
    if (q3.nodes[inner + l].weight > 0) by_weight.emplace_back(total += q3.nodes[inner + l].weight, l);
  if (by_weight.empty()) throw Error(map.path, 0, "the play space is empty: no leaf a player's eye can be in");
  std::vector<Vec3> points(count);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count, 1024), [&](const tbb::blocked_range<uint32_t>& r) {
    for (uint32_t i = r.begin(); i < r.end(); ++i) {
      Rng rng(seed, i);
      const auto it = std::lower_bound(by_weight.begin(), by_weight.end(), std::make_pair(rng.uniform() * total, 0));
      const int32_t l = (it == by_weight.end() ? by_weight.back() : *it).second;
      const Box3 b = q3.cells[inner + l].bounds();
      Vec3 p = b.center();
      for (int tries = 0; tries < 1000; ++tries) {
        const Vec3 q{rng.uniform(b.lo.x, b.hi.x), rng.uniform(b.lo.y, b.hi.y), rng.uniform(b.lo.z, b.hi.z)};
        if (map.leaf_at(q) == l) {
          p = q;
          break;
        }
      }
      points[i] = p;
    }
  });
  return points;
}

/// The map's non-solid space: the leaves with a cluster, outside their detail brushes.
class MapViewSpace : public ViewSpace {
 public:
  explicit MapViewSpace(std::shared_ptr<const Q3Map> map) : map_(std::move(map)) {}

  std::string describe() const override {
    size_t open = 0;
    for (const Q3Leaf& l : map_->leaves) open += l.cluster >= 0;
    return "the map's non-solid space (" + std::to_string(open) + " of " + std::to_string(map_->leaves.size()) +
           " leaves): sample origins in solid leaves are drawn again";
  }

  void restrict(SamplerConfig& config) const override {
    std::shared_ptr<const Q3Map> map = map_;
    config.view_space = [map](const Vec3& p) { return q3_in_view_space(*map, p); };
    if (config.view_box.empty()) config.view_box = q3_view_box(*map);
  }

  bool knows_players() const override { return true; }
  std::string box_rule() const override { return "the map's non-solid leaves"; }

  void restrict(AgvsConfig& config) const override {
    std::shared_ptr<const Q3Map> map = map_;
    config.view_space = [map](const Vec3& p) { return q3_in_view_space(*map, p); };
  }

  Box3 covered_box(const Box3& box) const override {
    Box3 out = box;
    out.extend(q3_cover_box(*map_));
    return out;
  }

  std::function<void(Subdivision&)> weigher(const Box3& box) const override {
    std::shared_ptr<const Subdivision> q3 = subdivision_over(box);
    return [q3](Subdivision& s) { weight_by_view_space(s, *q3); };
  }
  std::string weight_rule() const override { return "their volume in the map's " + space_name(); }

  std::shared_ptr<const ViewSpace> play_space(const Scene& scene, const RayCaster& caster) const override;

 protected:
  /// The map's BSP over `box` with the weights of this space's leaves.
  virtual Subdivision space_subdivision(const Box3& box) const { return q3_subdivision(*map_, box); }
  virtual std::string space_name() const { return "non-solid space"; }
  /// space_subdivision(box), kept for the last box asked: the division's viewpoints and then its
  /// weights ask for the same one.
  std::shared_ptr<const Subdivision> subdivision_over(const Box3& box) const {
    const std::lock_guard<std::mutex> lock(subdivision_mutex_);
    if (!subdivision_ || !(subdivision_box_ == box)) {
      subdivision_ = std::make_shared<const Subdivision>(space_subdivision(box));
      subdivision_box_ = box;
    }
    return subdivision_;
  }

  CameraSet place_cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& c,
                          const std::function<int32_t(const Vec3&)>& cell_at,
                          const CellLocator* locator) const override {
    (void)locator;
    CameraSet out;
    if (c.placement != CameraPlacement::kViewBox) {
      PlayCameraConfig pc = c.play;
      pc.count = c.count;
      pc.seed = c.seed;
      PlayCameras play = q3_play_cameras(*map_, scene, caster, pc);
      out.cameras = std::move(play.cameras);
      out.rule = play.rule;
      out.points_drawn = play.points_drawn;
      // A player's eye in no view cell is kept, and measured as a failure (measure_frames: an
      // engine gets no PVS there): the frame a player would see, not a reason to stop.
      for (const Camera& cam : out.cameras) out.cells.push_back(cell_at(cam.eye));
      return out;
    }
    // Uniform random points of the map's non-solid space (solid space sees nothing a player could).
    Rng rng(c.seed, 93);
    const Box3 box = q3_view_box(*map_);
    const uint64_t max_draws = 100000 + uint64_t{1000} * c.count;
    while (out.cameras.size() < c.count) {
      if (++out.points_drawn > max_draws)
        throw Error(map_->path, 0, "measure: too few camera positions in the map's non-solid space");
      const Vec3 eye{rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y), rng.uniform(box.lo.z, box.hi.z)};
      const Camera cam = camera_looking_anywhere(eye, rng);
      if (!q3_in_view_space(*map_, eye)) continue;
      const int32_t cell = cell_at(eye);
      if (cell < 0) continue;
      out.cameras.push_back(cam);
      out.cells.push_back(cell);
    }
    out.rule = "uniform random points of the map's non-solid space, looking anywhere";
    return out;
  }

  std::shared_ptr<const Q3Map> map_;

 private:
  mutable std::mutex subdivision_mutex_;
  mutable std::shared_ptr<const Subdivision> subdivision_;
  mutable Box3 subdivision_box_;
  mutable std::mutex play_mutex_;
  mutable std::shared_ptr<const ViewSpace> play_;
};

/// The play space: the non-solid leaves a player's eye can be in (q3_play_space). Segments are
/// still sampled in the whole non-solid space; the subdivision's viewpoints, the cells' weights
/// and AGVS's points come from the play leaves.
class PlayViewSpace final : public MapViewSpace, public std::enable_shared_from_this<PlayViewSpace> {
 public:
  PlayViewSpace(std::shared_ptr<const Q3Map> map, PlaySpace play)
      : MapViewSpace(std::move(map)), play_(std::make_shared<const PlaySpace>(std::move(play))) {}

  using MapViewSpace::restrict;

  void restrict(AgvsConfig& config) const override {
    const std::shared_ptr<const std::vector<bool>> play(play_, &play_->leaves);  // shares its ownership
    std::shared_ptr<const Q3Map> map = map_;
    // The play leaves' bounds, drawn by volume: a point of leaf l's bounds counts when it lies in
    // l (and outside its detail brushes), so the points are uniform over the play leaves however
    // their bounds overlap.
    const Subdivision q3 = q3_subdivision(*map, q3_view_box(*map));
    const int32_t inner = static_cast<int32_t>(map->nodes.size());
    struct Leaf {
      double upto;  ///< the bounds' volume of the leaves so far, this one's included
      int32_t leaf;
      Box3 bounds;
    };
    auto leaves = std::make_shared<std::vector<Leaf>>();
    double total = 0;
    for (int32_t l = 0; l < static_cast<int32_t>(play->size()); ++l) {
      if (!(*play)[l] || q3.cells[inner + l].empty()) continue;
      const Box3 b = q3.cells[inner + l].bounds();
      if (!(b.volume() > 0)) continue;
      leaves->push_back({total += b.volume(), l, b});
    }
    if (leaves->empty()) throw Error(map->path, 0, "the play space is empty: no leaf a player's eye can be in");
    config.view_point_map = [map, leaves, total](double u0, double u1, double u2) {
      const double at = u0 * total;
      const auto it = std::lower_bound(leaves->begin(), leaves->end(), at,
                                       [](const Leaf& x, double v) { return x.upto <= v; });
      const Leaf& x = it == leaves->end() ? leaves->back() : *it;
      const double from = x.upto - x.bounds.volume();
      const double f = std::clamp((at - from) / x.bounds.volume(), 0.0, 1.0);
      const Vec3 e = x.bounds.extent();
      const Vec3 p{x.bounds.lo.x + e.x * f, x.bounds.lo.y + e.y * u1, x.bounds.lo.z + e.z * u2};
      if (map->leaf_at(p) != x.leaf || !q3_in_view_space(*map, p)) return Vec3{std::nan(""), 0, 0};
      return p;
    };
    // REF draws its points in cells, and reports ask whether the points are restricted.
    config.view_space = [map, play](const Vec3& p) { return (*play)[map->leaf_at(p)] && q3_in_view_space(*map, p); };
  }

  void set_viewpoints(SubdivisionConfig& config, const Box3& box) const override {
    // Points uniform in the play leaves are the division's viewpoint density.
    config.viewpoints = std::make_shared<const std::vector<Vec3>>(
        uniform_points(*subdivision_over(box), *map_, kPlayViewpoints, config.seed + 0x5eed'0001));
  }
  std::string viewpoint_rule() const override { return play_->rule; }

  /// The play space is its own.
  std::shared_ptr<const ViewSpace> play_space(const Scene&, const RayCaster&) const override {
    return shared_from_this();
  }

 protected:
  Subdivision space_subdivision(const Box3& box) const override {
    Subdivision q3 = q3_subdivision(*map_, box);
    keep_leaf_weights(q3, *map_, play_->leaves);
    return q3;
  }
  std::string space_name() const override { return "play space"; }

 private:
  std::shared_ptr<const PlaySpace> play_;
};

std::shared_ptr<const ViewSpace> MapViewSpace::play_space(const Scene& scene, const RayCaster& caster) const {
  const std::lock_guard<std::mutex> lock(play_mutex_);
  if (!play_)
    play_ = std::make_shared<const PlayViewSpace>(map_, q3_play_space(*map_, scene, caster, PlaySpaceConfig{}));
  return play_;
}

}  // namespace

std::shared_ptr<const ViewSpace> q3_map_view_space(std::shared_ptr<const Q3Map> map) {
  if (!map) throw Error("a Quake 3 view space needs its map");
  return std::make_shared<const MapViewSpace>(std::move(map));
}

}  // namespace viewcells
