/// The play space of any triangle scene (viewspace/floor_space.h): floors under columns of
/// rays, joined by a player's moves, flooded from start points.
#include "viewcells/viewspace/floor_space.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <string_view>
#include <tuple>

#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/core/rng.h"
#include "viewcells/core/union_find.h"

namespace viewcells {

WalkableFloors::WalkableFloors(const Scene& scene, double walk_normal) {
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
    const ObjectInfo& o = scene.objects[scene.triangle_object[t]];
    if (!o.rendered || !o.occluder) continue;
    const Vec3 n = scene.triangle_normal(t);
    const double twice_area = length(n);
    if (!(twice_area > 0) || n.z < walk_normal * twice_area) continue;
    total_ += 0.5 * twice_area;
    floors_.emplace_back(total_, t);
  }
}

Vec3 WalkableFloors::point(const Scene& scene, double pick, double u, double v) const {
  const auto it = std::lower_bound(floors_.begin(), floors_.end(), std::make_pair(pick * total_, uint32_t{0}));
  const auto& tri = scene.triangles[(it == floors_.end() ? floors_.back() : *it).second];
  const double su = std::sqrt(u);
  return scene.vertices[tri[0]] * (1 - su) + scene.vertices[tri[1]] * (su * (1 - v)) + scene.vertices[tri[2]] * (su * v);
}

namespace {

const Vec3 kDown{0, 0, -1};
constexpr uint32_t kMaxHitsPerColumn = 1024;
/// Viewpoints drawn in the play space as the subdivision's viewpoint density (as on a map).
constexpr uint32_t kViewpoints = 200000;

}  // namespace

bool sky_name(const std::string& name) {
  // "skies" holds no "sky": both are looked for, case aside, with no copy (this runs per hit).
  const auto holds = [&](std::string_view word) {
    return std::search(name.begin(), name.end(), word.begin(), word.end(), [](char a, char b) {
             return std::tolower(static_cast<unsigned char>(a)) == b;
           }) != name.end();
  };
  return holds("sky") || holds("skies");
}

bool walkable_floor_hit(const Scene& scene, const Hit& hit, double walk_normal) {
  const ObjectInfo& o = scene.objects[hit.object];
  if (sky_name(o.name)) return false;
  // A closed object wound inside out (all its normals inward) has its outside on their backs.
  const bool inward = o.closed && o.oriented && o.signed_volume < 0;
  if (hit.front == inward || !o.rendered) return false;
  const Vec3 n = scene.triangle_normal(hit.triangle) * (inward ? -1.0 : 1.0);
  return n.z >= walk_normal * length(n) && n.z > 0;
}

std::vector<FloorSpace::FloorRect> FloorSpace::floor_rects() const {
  // Per row, the reached spans by (height, column): a run of next columns at one height is a
  // rectangle.
  std::vector<FloorRect> out;
  const double same = 0.001 / mpu_;
  std::vector<std::tuple<int64_t, int64_t, double>> row;  // (height in mm, column, height)
  for (int64_t y = 0; y < ny_; ++y) {
    row.clear();
    for (int64_t x = 0; x < nx_; ++x)
      for (uint32_t s = first_[y * nx_ + x]; s < first_[y * nx_ + x + 1]; ++s)
        if (reached_[s] && band_of(spans_[s]) > 0) row.emplace_back(std::llround(spans_[s].floor / same), x, spans_[s].floor);
    std::sort(row.begin(), row.end());
    for (size_t i = 0; i < row.size();) {
      size_t j = i + 1;
      while (j < row.size() && std::get<0>(row[j]) == std::get<0>(row[i]) &&
             std::get<1>(row[j]) == std::get<1>(row[j - 1]) + 1)
        ++j;
      const double yl = y0_ + static_cast<double>(y) * cell_;
      out.push_back({x0_ + static_cast<double>(std::get<1>(row[i])) * cell_, yl,
                     x0_ + static_cast<double>(std::get<1>(row[j - 1]) + 1) * cell_, yl + cell_, std::get<2>(row[i])});
      i = j;
    }
  }
  return out;
}

int64_t FloorSpace::column_of(double x, double y) const {
  const double fx = std::floor((x - x0_) / cell_), fy = std::floor((y - y0_) / cell_);
  if (!(fx >= 0 && fy >= 0 && fx < static_cast<double>(nx_) && fy < static_cast<double>(ny_))) return -1;
  return static_cast<int64_t>(fy) * nx_ + static_cast<int64_t>(fx);
}

double FloorSpace::band_of(const Span& s) const {
  return std::max(0.0, std::min({s.floor + u_.eye_high, s.ceiling, top_}) - (s.floor + u_.eye_low));
}

bool FloorSpace::contains(const Vec3& p) const {
  if (empty() || !box_.contains(p) || p.z > top_) return false;
  const Hit hit = caster_->intersect(Ray{p, kDown, 0, u_.eye_high});
  if (!hit.hit() || hit.t < u_.eye_low || !walkable_floor_hit(*scene_, hit, u_.walk_normal)) return false;
  const double floor = p.z - hit.t;
  const int64_t c = column_of(p.x, p.y);
  if (c < 0) return false;
  const int64_t cx = c % nx_, cy = c / nx_;
  for (int64_t y = std::max<int64_t>(cy - 1, 0); y <= std::min(cy + 1, ny_ - 1); ++y)
    for (int64_t x = std::max<int64_t>(cx - 1, 0); x <= std::min(cx + 1, nx_ - 1); ++x) {
      const int64_t n = y * nx_ + x;
      for (uint32_t s = first_[n]; s < first_[n + 1]; ++s)
        if (reached_[s] && std::abs(spans_[s].floor - floor) <= u_.step) return true;
    }
  return false;
}

Vec3 FloorSpace::point(double u0, double u1, double u2) const {
  const Vec3 none{std::nan(""), 0, 0};
  if (empty()) return none;
  const double at = u0 * band_volume_;
  const auto it = std::lower_bound(by_band_.begin(), by_band_.end(), std::make_pair(at, uint32_t{0}));
  const auto& [upto, s] = it == by_band_.end() ? by_band_.back() : *it;
  const double volume = band_of(spans_[s]) * cell_ * cell_;
  const double f = std::clamp((at - (upto - volume)) / volume, 0.0, 1.0);
  const int64_t c = std::upper_bound(first_.begin(), first_.end(), s) - first_.begin() - 1;
  const double x = x0_ + (static_cast<double>(c % nx_) + f) * cell_, y = y0_ + (static_cast<double>(c / nx_) + u1) * cell_;
  const Vec3 p{x, y, spans_[s].floor + u_.eye_low + u2 * band_of(spans_[s])};
  return contains(p) ? p : none;
}

std::vector<Vec3> FloorSpace::uniform_points(uint32_t count, uint64_t seed) const {
  if (empty()) throw Error("the play space is empty: no floor a player can reach");
  std::vector<Vec3> out(count);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count, 1024), [&](const tbb::blocked_range<uint32_t>& r) {
    for (uint32_t i = r.begin(); i < r.end(); ++i) {
      Rng rng(seed, i);
      Vec3 p{std::nan(""), 0, 0};
      // Points near walls miss contains(); after 1,000 misses the column's centre stands in.
      for (int tries = 0; tries < 1000 && std::isnan(p.x); ++tries) {
        const double a = rng.uniform(), b = rng.uniform(), c = rng.uniform();
        p = point(a, b, c);
        if (tries == 999 && std::isnan(p.x)) p = point(a, 0.5, 0.5);
      }
      out[i] = std::isnan(p.x) ? box_.center() : p;
    }
  });
  return out;
}

FloorSpace find_floor_space(const Scene& scene, const RayCaster& caster, const FloorSpaceConfig& config) {
  if (!(config.metres_per_unit >= 0 && std::isfinite(config.metres_per_unit)))
    throw Error("play space: metres per unit must be positive (or 0: the scene's own)");
  const double mpu = config.metres_per_unit > 0 ? config.metres_per_unit
                                                 : (scene.metres_per_unit > 0 ? scene.metres_per_unit : 1.0);
  const std::string unit_words = config.metres_per_unit > 0 ? "1 unit = " + fmt(mpu, 4) + " m (given)"
                                 : scene.metres_per_unit > 0 ? "1 unit = " + fmt(mpu, 4) + " m (from the file)"
                                                             : "units taken as metres (the file does not say)";
  if (!(mpu > 0 && std::isfinite(mpu))) throw Error("play space: metres per unit must be positive");
  const FloorSpaceConfig& c = config;
  if (!(c.cell > 0 && c.player_height > 0 && c.step >= 0 && c.eye_low >= 0 && c.eye_high > c.eye_low &&
        c.walk_normal > 0 && c.walk_normal <= 1 && c.min_region >= 0 && c.region_margin >= 0 && c.max_columns > 0))
    throw Error("play space: cell, player height and eye band must be positive (eye_low < eye_high), the step and "
                "region size not negative, the walkable normal in (0, 1]");
  FloorSpace out;
  out.scene_ = &scene;
  out.caster_ = &caster;
  out.u_ = config;
  out.mpu_ = mpu;
  FloorSpaceConfig& u = out.u_;
  for (double* d : {&u.cell, &u.player_height, &u.step, &u.eye_low, &u.eye_high, &u.region_margin}) *d /= mpu;
  u.min_region /= mpu * mpu;
  if (u.start_points.empty()) u.start_points = scene.start_points;
  const Box3& b = scene.bounds;
  if (b.empty()) throw Error(scene.source, 0, "play space: the scene has no geometry");
  out.top_ = b.hi.z;  // an eye above all of the scene (on its highest roof) looks at nothing a level holds
  const Vec3 e = b.extent();
  double cell = u.cell;
  // A grid of at most max_columns: the cell grows on a large level.
  const double columns = std::ceil(e.x / cell + 1) * std::ceil(e.y / cell + 1);
  if (columns > c.max_columns) cell *= std::sqrt(columns / c.max_columns) * 1.001;
  out.cell_ = cell;
  // Column centres off the round numbers a level is modelled on (walls, edges and stair risers at
  // whole or half units), so that no column runs down an edge or a face.
  out.x0_ = b.lo.x - 0.6180339887 * cell;
  out.y0_ = b.lo.y - 0.3819660113 * cell;
  out.nx_ = static_cast<int64_t>(std::ceil((b.hi.x - out.x0_) / cell)) + 1;
  out.ny_ = static_cast<int64_t>(std::ceil((b.hi.y - out.y0_) / cell)) + 1;
  const int64_t n = out.nx_ * out.ny_;
  const double top = b.hi.z + std::max(1.0, e.z * 1e-3), eps = cell * 1e-3;
  const double length = top - b.lo.z + 1;

  // 1. Floors: per column, the walkable surfaces a ray going down meets, each with the first
  // surface above it, kept when a standing player fits between.
  std::vector<std::vector<FloorSpace::Span>> found(n);
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n, 256), [&](const tbb::blocked_range<int64_t>& r) {
    for (int64_t col = r.begin(); col < r.end(); ++col) {
      const Vec3 o{out.x0_ + (static_cast<double>(col % out.nx_) + 0.5) * cell,
                   out.y0_ + (static_cast<double>(col / out.nx_) + 0.5) * cell, top};
      double above = std::numeric_limits<double>::infinity(), t = 0;
      for (uint32_t k = 0; k < kMaxHitsPerColumn; ++k) {
        const Hit hit = caster.intersect(Ray{o, kDown, t, length});
        if (!hit.hit()) break;
        const double z = top - hit.t;
        if (walkable_floor_hit(scene, hit, u.walk_normal) && above - z >= u.player_height)
          found[col].push_back({z, above});
        above = z;
        t = hit.t + eps;
      }
      std::reverse(found[col].begin(), found[col].end());  // lowest first
    }
  });
  out.first_.assign(n + 1, 0);
  for (int64_t col = 0; col < n; ++col) {
    out.first_[col + 1] = out.first_[col] + static_cast<uint32_t>(found[col].size());
    out.spans_.insert(out.spans_.end(), found[col].begin(), found[col].end());
  }
  found.clear();
  found.shrink_to_fit();
  const size_t spans = out.spans_.size();
  const auto centre = [&](int64_t col, double z) {
    return Vec3{out.x0_ + (static_cast<double>(col % out.nx_) + 0.5) * cell,
                out.y0_ + (static_cast<double>(col / out.nx_) + 0.5) * cell, z};
  };

  // 2. Moves: from a span to one of a side neighbour's when the neighbour's floor is at most a
  // step higher (or any amount lower: a drop), a standing player fits over both floors, and
  // nothing stands between the columns at a player's knee and head.
  std::vector<std::vector<uint32_t>> moves(spans);
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n, 256), [&](const tbb::blocked_range<int64_t>& r) {
    for (int64_t col = r.begin(); col < r.end(); ++col) {
      const int64_t cx = col % out.nx_, cy = col / out.nx_;
      const int64_t next[4][2] = {{cx - 1, cy}, {cx + 1, cy}, {cx, cy - 1}, {cx, cy + 1}};
      for (uint32_t a = out.first_[col]; a < out.first_[col + 1]; ++a) {
        const FloorSpace::Span& sa = out.spans_[a];
        for (const auto& [x, y] : next) {
          if (x < 0 || y < 0 || x >= out.nx_ || y >= out.ny_) continue;
          const int64_t ncol = y * out.nx_ + x;
          for (uint32_t bs = out.first_[ncol]; bs < out.first_[ncol + 1]; ++bs) {
            const FloorSpace::Span& sb = out.spans_[bs];
            const double lo = std::max(sa.floor, sb.floor);
            if (sb.floor > sa.floor + u.step || lo + u.player_height > std::min(sa.ceiling, sb.ceiling)) continue;
            bool free = true;
            for (double h : {0.25, 0.9}) {
              const Vec3 from = centre(col, lo + h * u.player_height), to = centre(ncol, lo + h * u.player_height);
              if (caster.intersect(Ray{from, normalize(to - from), 0, cell}).hit()) free = false;
            }
            if (free) moves[a].push_back(bs);
          }
        }
      }
    }
  });

  // 3. Starts: the span under each start point (the highest floor at most a step above it: a
  // start in the air falls to the floor below, in its column or the nearest ones around), then
  // the large enough regions of spans joined by walking both ways (FloorSpaceConfig::start_points).
  std::vector<uint32_t> stack;
  size_t starts_found = 0;
  for (const Vec3& p : u.start_points) {
    const int64_t col = out.column_of(p.x, p.y);
    if (col < 0) continue;
    const int64_t cx = col % out.nx_, cy = col / out.nx_;
    int64_t best = -1;
    for (int64_t ring = 0; ring <= 2 && best < 0; ++ring)
      for (int64_t y = std::max<int64_t>(cy - ring, 0); y <= std::min(cy + ring, out.ny_ - 1); ++y)
        for (int64_t x = std::max<int64_t>(cx - ring, 0); x <= std::min(cx + ring, out.nx_ - 1); ++x) {
          const int64_t m = y * out.nx_ + x;
          for (uint32_t s = out.first_[m]; s < out.first_[m + 1]; ++s) {
            const double f = out.spans_[s].floor;
            if (f <= p.z + u.step && (best < 0 || f > out.spans_[best].floor))
              best = s;
          }
        }
    if (best >= 0) {
      stack.push_back(static_cast<uint32_t>(best));
      ++starts_found;
    }
  }
  std::string start_words;
  if (!u.start_points.empty())
    start_words = "reachable from " + std::to_string(starts_found) + " of " + std::to_string(u.start_points.size()) +
                  " start points";
  // What the start points reach, flooded first: its box, grown by region_margin, bounds where
  // regions join it (a level's backdrop around the playable part is a region too).
  out.reached_.assign(spans, 0);
  const auto flood = [&](std::vector<uint32_t>& from, const Box3* within) {
    for (uint32_t s : from) out.reached_[s] = 1;
    while (!from.empty()) {
      const uint32_t a = from.back();
      from.pop_back();
      for (uint32_t bs : moves[a]) {
        if (out.reached_[bs]) continue;
        if (within) {
          const int64_t col = std::upper_bound(out.first_.begin(), out.first_.end(), bs) - out.first_.begin() - 1;
          if (!within->contains(centre(col, out.spans_[bs].floor))) continue;
        }
        out.reached_[bs] = 1;
        from.push_back(bs);
      }
    }
  };
  flood(stack, nullptr);
  if (u.start_points.empty() || !u.only_from_starts) {
    Box3 near;  // empty: no start points, every region joins
    if (!u.start_points.empty()) {
      for (int64_t col = 0; col < n; ++col)
        for (uint32_t s = out.first_[col]; s < out.first_[col + 1]; ++s)
          if (out.reached_[s]) near.extend(centre(col, out.spans_[s].floor));
      if (near.empty()) near.extend(Vec3{0, 0, 0});  // no start point found a floor: nothing joins
      const double m = u.region_margin;
      near = Box3{near.lo - Vec3{m, m, std::numeric_limits<double>::infinity()},
                  near.hi + Vec3{m, m, std::numeric_limits<double>::infinity()}};
      if (starts_found == 0) near = Box3{};
    }
    UnionFind regions(spans);
    for (uint32_t a = 0; a < spans; ++a)
      for (uint32_t bs : moves[a])
        if (std::find(moves[bs].begin(), moves[bs].end(), a) != moves[bs].end()) regions.unite(a, bs);
    std::vector<uint32_t> size(spans, 0);
    for (uint32_t a = 0; a < spans; ++a) ++size[regions.find(a)];
    const double cell_area = cell * cell;
    const bool bounded = !u.start_points.empty();
    std::vector<uint8_t> joined(spans, 0);
    for (int64_t col = 0; col < n; ++col)
      for (uint32_t a = out.first_[col]; a < out.first_[col + 1]; ++a)
        if (size[regions.find(a)] * cell_area >= u.min_region && !out.reached_[a] &&
            (!bounded || (!near.empty() && near.contains(centre(col, out.spans_[a].floor))))) {
          stack.push_back(a);
          joined[regions.find(a)] = 1;
        }
    const size_t kept = static_cast<size_t>(std::count(joined.begin(), joined.end(), 1));
    if (bounded && !near.empty()) flood(stack, &near);
    else if (!bounded) flood(stack, nullptr);
    const std::string regions_words =
        "every floor region of at least " + fmt(c.min_region, 1) + " m^2 (" + std::to_string(kept) + ")";
    start_words = !bounded ? "no start points: from " + regions_words
                           : start_words + " and from " + regions_words + " within " + fmt(c.region_margin, 1) +
                                 " m of what they reach (places walking misses, such as jump pads' and "
                                 "teleporters' destinations)";
  }
  for (int64_t col = 0; col < n; ++col)
    for (uint32_t s = out.first_[col]; s < out.first_[col + 1]; ++s) {
      if (!out.reached_[s]) continue;
      ++out.reached_count_;
      const double band = out.band_of(out.spans_[s]);
      if (!(band > 0)) continue;  // a roof at the scene's top: no eye above it
      out.reached_area_ += cell * cell;
      out.band_volume_ += band * cell * cell;
      out.by_band_.emplace_back(out.band_volume_, s);
      const Vec3 lo = centre(col, out.spans_[s].floor + u.eye_low) - Vec3{0.5 * cell, 0.5 * cell, 0};
      out.box_.extend(lo);
      out.box_.extend(lo + Vec3{cell, cell, band});
    }
  out.rule_ = "player eyes " + fmt(c.eye_low, 2) + "-" + fmt(c.eye_high, 2) + " m above walkable floors (normal z >= " +
             fmt(c.walk_normal, 2) + ", " + fmt(c.player_height, 2) + " m free above; steps up to " + fmt(c.step, 2) +
             " m, drops any height) " + start_words + "; " + unit_words + "; " + std::to_string(out.reached_count_) +
             " of " + std::to_string(spans) + " floor spans in columns " + fmt(cell * mpu, 3) + " m apart, floor area " +
             fmt(out.reached_area_ * mpu * mpu, 1) + " m^2";
  if (spans == 0) out.rule_ = "no walkable floor with " + fmt(c.player_height, 2) + " m free above it (" + unit_words + ")";
  else if (out.empty()) out.rule_ = "no floor reached: " + out.rule_;
  return out;
}

namespace {

/// The play space found from the floors.
class FloorViewSpace final : public ViewSpace, public std::enable_shared_from_this<FloorViewSpace> {
 public:
  explicit FloorViewSpace(std::shared_ptr<const FloorSpace> space) : space_(std::move(space)) {}

  std::string describe() const override { return "the play space found from the scene's floors"; }
  void restrict(AgvsConfig& config) const override {
    std::shared_ptr<const FloorSpace> s = space_;
    config.view_point_map = [s](double u0, double u1, double u2) { return s->point(u0, u1, u2); };
    config.view_space = [s](const Vec3& p) { return s->contains(p); };
  }
  void set_viewpoints(SubdivisionConfig& config, const Box3& box) const override {
    (void)box;
    config.viewpoints =
        std::make_shared<const std::vector<Vec3>>(space_->uniform_points(kViewpoints, config.seed + 0x5eed'0001));
  }
  std::string viewpoint_rule() const override { return space_->rule(); }
  bool knows_players() const override { return true; }
  std::shared_ptr<const ViewSpace> play_space(const Scene&, const RayCaster&) const override {
    return shared_from_this();
  }

 protected:
  CameraSet place_cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& c,
                          const std::function<int32_t(const Vec3&)>& cell_at, const CellLocator* locator) const override {
    if (c.placement == CameraPlacement::kViewBox) return box_view_space()->cameras(scene, caster, c, cell_at, locator);
    const FloorSpaceConfig& u = space_->units();
    const WalkableFloors floors(scene, u.walk_normal);
    const double eye = std::clamp(0.5 * (u.eye_low + u.player_height), u.eye_low, u.eye_high);
    const double pitch = c.play.max_pitch_degrees * std::numbers::pi / 180;
    const Vec3 up{0, 0, 1};
    CameraSet out;
    Rng rng(c.seed, 94);
    const uint64_t max_draws = 20000 + uint64_t{1000} * c.count;
    while (out.cameras.size() < c.count) {
      if (floors.empty() || ++out.points_drawn > max_draws)
        throw Error(scene.source, 0, "play cameras: only " + std::to_string(out.cameras.size()) + " of " +
                                         std::to_string(c.count) + " found on the play space's floors");
      const double pick = rng.uniform(), su = rng.uniform(), v = rng.uniform();
      const double yaw = 2 * std::numbers::pi * rng.uniform(), look = pitch * (2 * rng.uniform() - 1);
      const Vec3 f = floors.point(scene, pick, su, v);
      const double lift = 1e-3 * u.player_height;
      if (caster.intersect(Ray{f + up * lift, up, 0, u.player_height - lift}).hit()) continue;
      if (!space_->contains(f + up * eye)) continue;
      out.cameras.push_back(camera_looking(f + up * eye, yaw, look));
      out.cells.push_back(cell_at(out.cameras.back().eye));
    }
    out.rule = "player eyes " + fmt(eye * space_->metres_per_unit(), 2) +
               " m above the play space's floors (uniform by area); yaw uniform, pitch uniform within +-" +
               fmt(c.play.max_pitch_degrees, 0) + " degrees, no roll";
    return out;
  }

 private:
  std::shared_ptr<const FloorSpace> space_;
};

/// The whole view box, whose play space is found from the floors when first asked.
class MeshViewSpace final : public ViewSpace {
 public:
  explicit MeshViewSpace(FloorSpaceConfig config) : config_(std::move(config)) {}

  std::string describe() const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    return "the whole view box" + (asked_ && !play_ ? " (no play space: " + why_ + ")" : std::string());
  }
  bool may_know_players() const override { return true; }

  std::shared_ptr<const ViewSpace> play_space(const Scene& scene, const RayCaster& caster) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!asked_) {
      asked_ = true;
      auto space = std::make_shared<const FloorSpace>(find_floor_space(scene, caster, config_));
      if (space->empty()) {
        why_ = space->rule();
      } else {
        play_box_ = space->box();
        scene_box_ = scene.bounds;
        play_ = floor_view_space(std::move(space));
      }
    }
    return play_;
  }
  /// Once the play space is found (a bake asks before it samples), segments are sampled in its
  /// box, as a map's in its non-solid leaves: the construction samples where players are.
  void restrict(SamplerConfig& config) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (play_ && config.view_box.empty()) config.view_box = play_box_;
  }
  std::string box_rule() const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    return play_ ? "the play space's box" : "scene bounds";
  }
  /// The file still covers the whole scene: an engine finds a cell wherever a camera goes.
  Box3 covered_box(const Box3& box) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    Box3 out = box;
    if (play_) out.extend(scene_box_);
    return out;
  }
  std::string no_play_space_reason() const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    return asked_ ? why_ : std::string();
  }

 protected:
  CameraSet place_cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& c,
                          const std::function<int32_t(const Vec3&)>& cell_at, const CellLocator* locator) const override {
    if (c.placement == CameraPlacement::kPlay) {
      const std::shared_ptr<const ViewSpace> play = play_space(scene, caster);
      if (!play) throw Error(scene.source, 0, "play cameras: the scene has no play space: " + no_play_space_reason());
      return play->cameras(scene, caster, c, cell_at, locator);
    }
    // Auto keeps the view box: a scene's floors are found for a bake, not assumed for a measure.
    return box_view_space()->cameras(scene, caster, c, cell_at, locator);
  }

 private:
  FloorSpaceConfig config_;
  mutable std::mutex mutex_;
  mutable bool asked_ = false;
  mutable std::string why_;
  mutable std::shared_ptr<const ViewSpace> play_;
  mutable Box3 play_box_, scene_box_;
};

}  // namespace

std::shared_ptr<const ViewSpace> floor_view_space(std::shared_ptr<const FloorSpace> space) {
  if (!space || space->empty()) throw Error("a play space from floors needs a floor a player can reach");
  return std::make_shared<const FloorViewSpace>(std::move(space));
}

std::shared_ptr<const ViewSpace> mesh_view_space(FloorSpaceConfig config) {
  return std::make_shared<const MeshViewSpace>(std::move(config));
}

}  // namespace viewcells
