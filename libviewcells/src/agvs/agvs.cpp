#include "viewcells/agvs/agvs.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>

#include "viewcells/agvs/penumbra.h"
#include "viewcells/bsp/adjacency.h"
#include "viewcells/core/error.h"
#include "viewcells/io/binary_file.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells {

// ------------------------------------------------------------------------------ cells, PVS

CellLocator::CellLocator(Subdivision bsp, std::vector<int32_t> leaf_cell, uint32_t cell_count)
    : bsp_(std::move(bsp)), leaf_cell_(std::move(leaf_cell)), cell_count_(cell_count) {
  if (bsp_.nodes.empty() || leaf_cell_.size() != bsp_.nodes.size()) throw Error("the view cells need a BSP");
  if (cell_count_ == 0) throw Error("there are no view cells");
  for (size_t n = 0; n < bsp_.nodes.size(); ++n)
    if (bsp_.nodes[n].plane < 0 && (leaf_cell_[n] < 0 || leaf_cell_[n] >= static_cast<int32_t>(cell_count_)))
      throw Error("BSP leaf " + std::to_string(n) + " has no view cell");
  bounds_.assign(cell_count_, Box3{});
  volume_.assign(cell_count_, 0.0);
  clip_to_leaves(bsp_, ConvexPolyhedron::box(bsp_.view_box, 0), [&](int32_t n, const ConvexPolyhedron& part) {
    bounds_[leaf_cell_[n]].extend(part.bounds());
    volume_[leaf_cell_[n]] += part.volume();
  });
  for (uint32_t c = 0; c < cell_count_; ++c)
    if (!(volume_[c] > 0)) throw Error("view cell " + std::to_string(c) + " has no volume");
}

int32_t CellLocator::cell_at(const Vec3& p) const {
  const int32_t leaf = bsp_.locate(p);
  return leaf < 0 ? -1 : leaf_cell_[leaf];
}

void CellLocator::cells_of_segment(const Vec3& a, const Vec3& b, std::vector<int32_t>& out,
                                   std::vector<std::tuple<int32_t, double, double>>& stack,
                                   std::vector<int32_t>& leaves) const {
  leaves.clear();
  bsp_.leaves_of_segment(a, b, leaves, stack);
  out.clear();
  for (int32_t l : leaves) out.push_back(leaf_cell_[l]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::vector<std::vector<uint32_t>> CellLocator::neighbours() const {
  std::vector<std::vector<uint32_t>> out(cell_count_);
  // The leaves' convex cells (a BSP read from a file has none), replayed from the view box.
  Subdivision with_cells = bsp_;
  with_cells.cells.assign(bsp_.nodes.size(), ConvexPolyhedron());
  clip_to_leaves(bsp_, ConvexPolyhedron::box(bsp_.view_box, 0),
                 [&](int32_t n, const ConvexPolyhedron& part) { with_cells.cells[n] = part; });
  std::vector<int32_t> leaves;
  for (size_t n = 0; n < bsp_.nodes.size(); ++n)
    if (bsp_.nodes[n].plane < 0) leaves.push_back(static_cast<int32_t>(n));
  for (const LeafAdjacency& a : leaf_adjacency(with_cells, leaves)) {
    const int32_t ca = leaf_cell_[a.a], cb = leaf_cell_[a.b];
    if (ca == cb) continue;
    out[ca].push_back(static_cast<uint32_t>(cb));
    out[cb].push_back(static_cast<uint32_t>(ca));
  }
  for (auto& list : out) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return out;
}

GlobalPvs::GlobalPvs(uint32_t cells, uint32_t objects)
    : cells_(cells), objects_(objects), words_((objects + 63) / 64), bits_(size_t(cells) * words_, 0), sizes_(cells, 0) {}

GlobalPvs GlobalPvs::from_lists(uint32_t objects, const std::vector<std::vector<uint32_t>>& lists) {
  GlobalPvs p(static_cast<uint32_t>(lists.size()), objects);
  for (uint32_t c = 0; c < lists.size(); ++c)
    for (uint32_t o : lists[c]) p.insert(c, o);
  return p;
}

bool GlobalPvs::insert(uint32_t cell, uint32_t object) {
  uint64_t& w = bits_[size_t(cell) * words_ + object / 64];
  const uint64_t bit = uint64_t{1} << (object % 64);
  if (w & bit) return false;
  w |= bit;
  ++sizes_[cell];
  ++entries_;
  return true;
}

bool GlobalPvs::erase(uint32_t cell, uint32_t object) {
  uint64_t& w = bits_[size_t(cell) * words_ + object / 64];
  const uint64_t bit = uint64_t{1} << (object % 64);
  if (!(w & bit)) return false;
  w &= ~bit;
  --sizes_[cell];
  --entries_;
  return true;
}

uint64_t GlobalPvs::common_entries(const GlobalPvs& other) const {
  if (other.cells_ != cells_ || other.objects_ != objects_) throw Error("PVS tables of different shapes");
  uint64_t n = 0;
  for (size_t w = 0; w < bits_.size(); ++w) n += static_cast<uint64_t>(__builtin_popcountll(bits_[w] & other.bits_[w]));
  return n;
}

std::vector<uint32_t> GlobalPvs::list(uint32_t cell) const {
  std::vector<uint32_t> out;
  out.reserve(sizes_[cell]);
  for (size_t w = 0; w < words_; ++w)
    for (uint64_t bits = bits_[size_t(cell) * words_ + w]; bits; bits &= bits - 1)
      out.push_back(static_cast<uint32_t>(w * 64 + __builtin_ctzll(bits)));
  return out;
}

uint32_t contribute(GlobalPvs& pvs, const std::vector<int32_t>& cells, uint32_t object_a, uint32_t object_b,
                    bool contributed[2], int32_t origin_cell, bool at_origin[2]) {
  const uint32_t objs[2] = {object_a, object_b};
  uint32_t gain = 0;
  for (int32_t cell : cells)
    for (int e = 0; e < 2; ++e) {
      if (objs[e] == kNoObject || (e == 1 && objs[1] == objs[0])) continue;
      if (!pvs.insert(static_cast<uint32_t>(cell), objs[e])) continue;
      ++gain;
      if (contributed) contributed[e] = true;
      if (at_origin && cell == origin_cell) at_origin[e] = true;
    }
  // Both ends see the same object: both rays were wrong pixels before.
  if (at_origin && objs[0] == objs[1] && objs[0] != kNoObject) at_origin[1] = at_origin[0];
  return gain;
}

AgvsMethod parse_agvs_method(const std::string& name) {
  if (name == "agvs") return AgvsMethod::kAgvs;
  if (name == "sgvs") return AgvsMethod::kSgvs;
  if (name == "ref") return AgvsMethod::kRef;
  throw Error("unknown PVS method '" + name + "' (expected agvs, sgvs or ref)");
}

const char* to_string(AgvsMethod m) {
  switch (m) {
    case AgvsMethod::kAgvs: return "agvs";
    case AgvsMethod::kSgvs: return "sgvs";
    case AgvsMethod::kRef: return "ref";
  }
  return "?";
}

const char* to_string(AgvsDistribution d) {
  switch (d) {
    case AgvsDistribution::kViewSpaceDirection: return "view space-direction";
    case AgvsDistribution::kObjectDirection: return "object-direction";
    case AgvsDistribution::kTwoPoint: return "two-point";
    case AgvsDistribution::kTwoPointMutation: return "two-point mutation";
    case AgvsDistribution::kSilhouetteMutation: return "silhouette mutation";
    case AgvsDistribution::kCount: break;
  }
  return "?";
}

std::vector<uint32_t> match_objects(const Scene& before, const Scene& after) {
  // Per object: its name and a hash of its triangles' corner coordinates, in order.
  auto keys = [](const Scene& s) {
    std::vector<ByteWriter> geometry(s.object_count());
    for (uint32_t t = 0; t < s.triangles.size(); ++t)
      for (uint32_t v : s.triangles[t]) geometry[s.triangle_object[t]].put(s.vertices[v]);
    std::vector<std::pair<std::string, uint64_t>> out;
    for (uint32_t o = 0; o < s.object_count(); ++o) out.emplace_back(s.objects[o].name, fnv1a64(geometry[o].data()));
    return out;
  };
  std::multimap<std::pair<std::string, uint64_t>, uint32_t> free;
  const auto after_keys = keys(after);
  for (uint32_t o = 0; o < after_keys.size(); ++o) free.emplace(after_keys[o], o);
  std::vector<uint32_t> new_of_old;
  for (const auto& key : keys(before)) {
    const auto it = free.find(key);  // the first among equals: multimap keeps insertion order
    if (it == free.end()) {
      new_of_old.push_back(kNoObject);
    } else {
      new_of_old.push_back(it->second);
      free.erase(it);
    }
  }
  return new_of_old;
}

// ------------------------------------------------------------------------------ the solver

namespace {

constexpr int kDists = static_cast<int>(AgvsDistribution::kCount);
constexpr int kVsd = 0, kOd = 1, kTp = 2, kTpm = 3, kSil = 4;

/// Radical inverse of i in base b: the Halton sequence's coordinate.
double radical_inverse(uint64_t i, uint32_t b) {
  double inv = 1.0 / b, f = inv, r = 0;
  while (i > 0) {
    r += f * static_cast<double>(i % b);
    i /= b;
    f *= inv;
  }
  return r;
}

/// Halton point `i` of a stream: coordinates in bases 2, 3, 5, ..., each rotated by a seeded
/// offset (Cranley-Patterson), so that seeds give different but equally even sequences.
struct Halton {
  static constexpr uint32_t kBases[7] = {2, 3, 5, 7, 11, 13, 17};
  double offset[7];
  Halton(uint64_t seed, uint64_t stream) {
    Rng rng(seed, stream);
    for (double& o : offset) o = rng.uniform();
  }
  double at(uint64_t i, int dim) const {
    const double x = radical_inverse(i + 1, kBases[dim]) + offset[dim];
    return x - std::floor(x);
  }
};

Vec3 sphere_direction(double u1, double u2) {
  const double phi = 2 * std::numbers::pi * u1, cos_theta = 1 - 2 * u2;
  const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

/// Bounding boxes in a median-split tree: which boxes touch a query box.
class BoxTree {
 public:
  explicit BoxTree(std::vector<std::pair<Box3, uint32_t>> items) : items_(std::move(items)) {
    if (items_.empty()) return;
    nodes_.resize(1);
    build(0, 0, static_cast<uint32_t>(items_.size()), 0);
  }
  void query(const Box3& q, std::vector<uint32_t>& out) const {
    if (nodes_.empty()) return;
    uint32_t stack[96];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!touches(n.bounds, q)) continue;
      if (n.left == 0) {
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
          if (touches(items_[i].first, q)) out.push_back(items_[i].second);
      } else {
        stack[top++] = n.left;
        stack[top++] = n.left + 1;
      }
    }
  }

 private:
  struct Node {
    Box3 bounds;
    uint32_t left = 0, first = 0, count = 0;  ///< left: first child (the second follows); 0: a leaf
  };
  static bool touches(const Box3& a, const Box3& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
  }
  void build(uint32_t id, uint32_t first, uint32_t last, int depth) {
    Box3 b, centres;
    for (uint32_t i = first; i < last; ++i) b.extend(items_[i].first), centres.extend(items_[i].first.center());
    nodes_[id].bounds = b;
    if (last - first <= 4 || depth >= 40) {
      nodes_[id].first = first, nodes_[id].count = last - first;
      return;
    }
    const Vec3 e = centres.extent();
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const uint32_t mid = first + (last - first) / 2;
    std::nth_element(items_.begin() + first, items_.begin() + mid, items_.begin() + last,
                     [axis](const auto& p, const auto& q) { return p.first.center()[axis] < q.first.center()[axis]; });
    const uint32_t left = static_cast<uint32_t>(nodes_.size());
    nodes_.resize(left + 2);
    nodes_[id].left = left;
    build(left, first, mid, depth + 1);
    build(left + 1, mid, last, depth + 1);
  }
  std::vector<std::pair<Box3, uint32_t>> items_;
  std::vector<Node> nodes_;
};

struct Candidate {
  Vec3 origin, term;           ///< the segment's other end, and the end where the object was seen
  double r_origin = 0, r_term = 0;  ///< radii of what lies at each end (object or view cell)
  uint32_t object = kNoObject;      ///< the object seen at `term`
};

/// A mutation strategy's candidates, the least mutated first (ties: the oldest); when full,
/// the most mutated (the newest among equals) is dropped.
struct CandidateBuffer {
  std::map<uint64_t, Candidate> candidates;
  std::set<std::pair<uint32_t, uint64_t>> by_count;
  std::map<uint64_t, uint32_t> count_of;
  uint64_t next_id = 0;

  bool empty() const { return by_count.empty(); }
  size_t size() const { return candidates.size(); }
  void add(const Candidate& c, size_t cap) {
    const uint64_t id = next_id++;
    candidates.emplace(id, c);
    by_count.insert({0u, id});
    count_of[id] = 0;
    if (candidates.size() > cap) {
      const auto last = std::prev(by_count.end());
      candidates.erase(last->second);
      count_of.erase(last->second);
      by_count.erase(last);
    }
  }
  /// The least mutated candidate; its count goes up by one.
  const Candidate& take() {
    const auto first = *by_count.begin();
    by_count.erase(by_count.begin());
    by_count.insert({first.first + 1, first.second});
    count_of[first.second] = first.first + 1;
    return candidates.at(first.second);
  }
  void save(ByteWriter& w) const {
    w.put(next_id);
    w.put<uint64_t>(candidates.size());
    for (const auto& [id, c] : candidates) {
      w.put(id), w.put(count_of.at(id));
      w.put(c.origin), w.put(c.term), w.put(c.r_origin), w.put(c.r_term), w.put(c.object);
    }
  }
  /// `box`: where candidate ends may lie (a state's candidates come from segments in the view
  /// box); `objects`: the scene's object count. Anything else is a corrupt state, refused here
  /// rather than cast (rays from 1e300 once reached Embree and aborted).
  static CandidateBuffer load(ByteReader& r, size_t cap, size_t payload, const Box3& box, uint32_t objects) {
    CandidateBuffer b;
    b.next_id = r.get<uint64_t>();
    const uint64_t n = r.get<uint64_t>();
    if (n > cap || n > payload) r.fail("too many mutation candidates");
    for (uint64_t k = 0; k < n; ++k) {
      const uint64_t id = r.get<uint64_t>();
      const uint32_t count = r.get<uint32_t>();
      Candidate c;
      c.origin = r.get<Vec3>(), c.term = r.get<Vec3>(), c.r_origin = r.get<double>(), c.r_term = r.get<double>();
      c.object = r.get<uint32_t>();
      const bool inside = box.contains(c.origin) && box.contains(c.term);  // false for NaN
      if (!inside || !(c.r_origin >= 0 && c.r_origin < 1e300) || !(c.r_term >= 0 && c.r_term < 1e300) ||
          (c.object != kNoObject && c.object >= objects))
        r.fail("a mutation candidate lies outside the view space or names no object");
      if (id >= b.next_id || !b.candidates.emplace(id, c).second) r.fail("mutation candidate ids are inconsistent");
      b.count_of[id] = count;
      b.by_count.insert({count, id});
    }
    return b;
  }
};

}  // namespace

struct AgvsSolver::Impl {
  const Scene* scene_;  ///< rebound by scene edits
  const CellLocator& cells;
  AgvsConfig config;
  const RayCaster* caster_ref_;
  std::unique_ptr<SegmentCaster> caster_;
  GlobalPvs pvs;
  AgvsStats stats;
  // Surface sampling: rendered objects, and each one's triangles by cumulative area.
  std::vector<uint32_t> objects;
  std::vector<std::vector<std::pair<double, uint32_t>>> triangles_of;
  std::vector<double> object_radius;
  Halton halton[kDists];
  uint64_t halton_index[kDists] = {};
  // Mutation candidates of the two mutation strategies.
  CandidateBuffer two_point, silhouette;
  // The mixture: contribution and rays of each distribution in the last batch.
  double weight[kDists] = {};
  double recent_contribution[kDists] = {}, recent_rays[kDists] = {};
  uint64_t last_calibration = 0;
  bool calibrated = false;
  // The pixel error estimator's window: per batch, view space-direction rays and those that
  // added an entry to the cell containing their origin.
  std::deque<std::pair<uint64_t, uint64_t>> window;
  uint64_t window_total = 0;  ///< camera rays since the start (or the last edit), trimmed ones too
  double error = std::numeric_limits<double>::quiet_NaN();
  /// With too few wrong camera rays for a window: the error's 90% upper bound, in pixels.
  double error_bound = std::numeric_limits<double>::quiet_NaN();
  double eps;  ///< offset of ray origins from surfaces
  // The visibility filter's sampling densities (config.filter_statistics): segments through
  // each cell, and per cell and object the segments through the cell that hit the object
  // (saturating).
  std::vector<uint64_t> cell_samples;
  std::vector<uint16_t> hit_counts;
  std::vector<GlobalPvs> references;  ///< for the curve's coverage only

  const Scene& scene() const { return *scene_; }
  const RayCaster& caster_ref() const { return *caster_ref_; }
  const SegmentCaster& caster() const { return *caster_; }

  Impl(const Scene& s, const RayCaster& rc, const CellLocator& c, const AgvsConfig& cfg)
      : cells(c),
        config(cfg),
        pvs(c.cell_count(), static_cast<uint32_t>(s.object_count())),
        halton{Halton(cfg.seed, 11), Halton(cfg.seed, 12), Halton(cfg.seed, 13), Halton(cfg.seed, 14),
               Halton(cfg.seed, 15)} {
    bind(s, rc);
    if (config.filter_statistics) {
      cell_samples.assign(c.cell_count(), 0);
      hit_counts.assign(size_t(c.cell_count()) * s.object_count(), 0);
    }
  }

  /// Takes the scene and its caster: what sampling derives from them.
  void bind(const Scene& s, const RayCaster& rc) {
    auto segment_caster = std::make_unique<SegmentCaster>(s, rc, cells.view_box(), config.empty_space);
    std::vector<std::vector<std::pair<double, uint32_t>>> tris(s.object_count());
    for (uint32_t t = 0; t < s.triangles.size(); ++t) {
      const double area = 0.5 * length(s.triangle_normal(t));
      auto& list = tris[s.triangle_object[t]];
      list.emplace_back((list.empty() ? 0.0 : list.back().first) + area, t);
    }
    std::vector<uint32_t> sampled;
    for (uint32_t o = 0; o < s.object_count(); ++o)
      if (s.objects[o].rendered && !tris[o].empty() && tris[o].back().first > 0) sampled.push_back(o);
    if (sampled.empty()) throw Error("the scene has no rendered object to sample");
    scene_ = &s;
    caster_ref_ = &rc;
    caster_ = std::move(segment_caster);
    stats.empty_space = caster_->empty_space();
    eps = 1e-6 * std::max(s.bounds.diagonal(), cells.view_box().diagonal());
    triangles_of = std::move(tris);
    objects = std::move(sampled);
    object_radius.clear();
    for (const ObjectInfo& o : s.objects) object_radius.push_back(0.5 * o.bounds.diagonal());
  }

  /// A point on a random rendered object from Halton coordinates (u0 object, u1 triangle,
  /// u2, u3 barycentric) and the triangle's unit normal.
  Vec3 object_point(double u0, double u1, double u2, double u3, Vec3& normal) const {
    const uint32_t o = objects[std::min<size_t>(static_cast<size_t>(u0 * objects.size()), objects.size() - 1)];
    const auto& list = triangles_of[o];
    const double target = u1 * list.back().first;
    const auto it = std::lower_bound(list.begin(), list.end(), std::make_pair(target, 0u));
    const uint32_t t = (it == list.end() ? list.back() : *it).second;
    const Scene& scene = this->scene();
    const auto& tri = scene.triangles[t];
    const double su = std::sqrt(u2);
    const Vec3 p = scene.vertices[tri[0]] * (1 - su) + scene.vertices[tri[1]] * (su * (1 - u3)) +
                   scene.vertices[tri[2]] * (su * u3);
    normal = normalize(scene.triangle_normal(t));
    return p;
  }

  Vec3 view_point(double u0, double u1, double u2) const {
    const Box3& b = cells.view_box();
    const Vec3 e = b.extent();
    return {b.lo.x + e.x * u0, b.lo.y + e.y * u1, b.lo.z + e.z * u2};
  }

  /// Draws one sample of distribution d into (point, dir); false when it cannot (no candidate).
  bool draw(int d, Rng& rng, Vec3& point, Vec3& dir) {
    const Halton& h = halton[d];
    switch (d) {
      case kVsd: {
        const uint64_t i = halton_index[d]++;
        point = view_point(h.at(i, 0), h.at(i, 1), h.at(i, 2));
        dir = sphere_direction(h.at(i, 3), h.at(i, 4));
        return true;
      }
      case kOd: {
        const uint64_t i = halton_index[d]++;
        Vec3 n;
        const Vec3 x = object_point(h.at(i, 0), h.at(i, 1), h.at(i, 2), h.at(i, 3), n);
        // Cosine-weighted about the normal: phi = 2 pi u, theta = acos(sqrt(v)).
        const double phi = 2 * std::numbers::pi * h.at(i, 4), cos_theta = std::sqrt(h.at(i, 5));
        const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
        Vec3 u, v;
        orthonormal_basis(n, u, v);
        dir = n * cos_theta + (u * std::cos(phi) + v * std::sin(phi)) * sin_theta;
        point = x + dir * eps;  // the backward ray comes back to x
        return true;
      }
      case kTp: {
        const uint64_t i = halton_index[d]++;
        Vec3 n;
        const Vec3 o = object_point(h.at(i, 0), h.at(i, 1), h.at(i, 2), h.at(i, 3), n);
        point = view_point(h.at(i, 4), h.at(i, 5), h.at(i, 6));
        const Vec3 to = o - point;
        if (!(length(to) > eps)) return false;
        dir = normalize(to);
        return true;
      }
      case kTpm: {
        if (two_point.empty()) return false;
        const Candidate& c = two_point.take();
        const Vec3 axis = c.term - c.origin;
        if (!(length(axis) > 0)) return false;
        Vec3 u, v;
        orthonormal_basis(normalize(axis), u, v);
        auto gauss2 = [&](double sigma) {
          // Box-Muller: two independent normals.
          const double r = sigma * std::sqrt(-2 * std::log(std::max(1e-300, 1 - rng.uniform())));
          const double a = 2 * std::numbers::pi * rng.uniform();
          return u * (r * std::cos(a)) + v * (r * std::sin(a));
        };
        const Vec3 o2 = c.origin + gauss2(c.r_origin), t2 = c.term + gauss2(c.r_term);
        const Vec3 d2 = t2 - o2;
        if (!(length(d2) > eps)) return false;
        point = (o2 + t2) * 0.5;  // the middle: away from local occlusion at either end
        dir = normalize(d2);
        if (!cells.view_box().contains(point)) return false;
        return true;
      }
    }
    return false;
  }

  void add_candidate(const Candidate& c) {
    two_point.add(c, config.mutation_buffer);
    silhouette.add(c, config.mutation_buffer);
  }

  /// Silhouette mutation (paper 4.4, after Wonka et al.'s adaptive border sampling): from the
  /// candidate's other end, discovery rays towards points moved off the seen object along a
  /// random direction of the plane through its end, perpendicular to the segment; the nearest
  /// one that misses the object (binary search) passes its silhouette. If that ray then hits
  /// something more than k r(o) beyond the moved point (a depth discontinuity), a second
  /// search runs along the jump. Returns the samples' points and directions (one or two).
  /// `angle_u`: the two uniform numbers that choose the directions of the two searches (drawn
  /// beforehand, so that searches run in parallel and stay reproducible); `rays` counts the
  /// discovery rays. Thread-safe.
  int silhouette_samples(const Candidate& c, const double angle_u[2], Vec3 points_out[2], Vec3 dirs_out[2],
                         uint64_t& rays) const {
    const double r = c.r_term;
    if (c.object == kNoObject || !(r > 0)) return 0;
    int searches = 0;
    auto search = [&](const Vec3& from, const Vec3& at, uint32_t object, double radius, Vec3& found) {
      const Vec3 axis = at - from;
      if (!(length(axis) > eps)) return false;
      Vec3 u, v;
      orthonormal_basis(normalize(axis), u, v);
      const double a = 2 * std::numbers::pi * angle_u[searches++];
      const Vec3 d = u * std::cos(a) + v * std::sin(a);
      auto hits_object = [&](double lambda) {
        const Vec3 target = at + d * (lambda * radius);
        // From just off `from`, which may lie on a surface itself.
        const Hit h = caster_ref().intersect(Ray{from, target - from, 1e-6, 1.0 + 1e-6});
        ++rays;
        return h.hit() && h.object == object;
      };
      if (hits_object(1.0)) return false;  // the object reaches past r along d: no silhouette here
      double lo = 0, hi = 1;
      for (int step = 0; step < 6; ++step) {
        const double mid = 0.5 * (lo + hi);
        (hits_object(mid) ? lo : hi) = mid;
      }
      found = at + d * (hi * radius);
      return true;
    };
    Vec3 moved;
    if (!search(c.origin, c.term, c.object, r, moved)) return 0;
    int n = 0;
    const Vec3 dir = moved - c.origin;
    if (!(length(dir) > eps)) return 0;
    points_out[n] = (c.origin + moved) * 0.5;
    dirs_out[n++] = normalize(dir);
    // Depth discontinuity: where does the silhouette ray really end?
    const Hit h = caster_ref().intersect(Ray{c.origin, normalize(dir), eps});
    ++rays;
    constexpr double kDepthJump = 3.0;  // the paper's k
    if (h.hit()) {
      const Vec3 end = c.origin + normalize(dir) * h.t;
      Vec3 moved2;
      if (length(end - moved) > kDepthJump * r && search(moved, end, h.object, object_radius[h.object], moved2)) {
        const Vec3 d2 = moved2 - moved;
        if (length(d2) > eps) {
          points_out[n] = (moved + moved2) * 0.5;
          dirs_out[n++] = normalize(d2);
        }
      }
    }
    return n;
  }

  /// The filter's densities: one more segment through `cell`, hitting objects a and b.
  void count_hits(int32_t cell, uint32_t a, uint32_t b) {
    ++cell_samples[cell];
    const size_t row = size_t(cell) * pvs.object_count();
    auto bump = [&](uint32_t o) {
      if (o == kNoObject) return;
      uint16_t& h = hit_counts[row + o];
      if (h < std::numeric_limits<uint16_t>::max()) ++h;
    };
    bump(a);
    if (b != a) bump(b);
  }

  /// Radius of what lies at a segment end: its object, or else the view cell there.
  double end_radius(uint32_t object, const Vec3& p) const {
    if (object != kNoObject) return object_radius[object];
    const int32_t c = cells.cell_at(p);
    return c >= 0 ? 0.5 * cells.cell_bounds(c).diagonal() : 0.0;
  }

  /// The shares of the next batch's samples.
  void shares(double share[kDists]) {
    std::fill(share, share + kDists, 0.0);
    if (config.method != AgvsMethod::kAgvs) {
      share[kVsd] = 1;
      return;
    }
    auto usable = [&](int d) {
      return (d != kTpm || !two_point.empty()) && (d != kSil || !silhouette.empty());
    };
    const bool calibrate = !calibrated || stats.samples - last_calibration >= config.recalibrate_every;
    // A distribution not tried yet (the mutation, before its first candidates) gets the
    // best weight: it is then measured like the others.
    const double best = *std::max_element(weight, weight + kDists);
    double total = 0;
    for (int d = 0; d < kDists; ++d) {
      const double w = recent_rays[d] > 0 ? weight[d] : best;
      share[d] = usable(d) ? (calibrate ? 1.0 : w) : 0.0;
      total += share[d];
    }
    if (!(total > 0)) {  // nothing contributed in the last batch: spread evenly
      for (int d = 0; d < kDists; ++d) share[d] = usable(d) ? 1.0 : 0.0;
      total = std::accumulate(share, share + kDists, 0.0);
    }
    for (int d = 0; d < kDists; ++d) share[d] /= total;
    if (share[kVsd] < config.min_share) {  // keep the estimator's rays coming
      const double rest = 1 - share[kVsd];
      for (int d = 1; d < kDists; ++d) share[d] *= (1 - config.min_share) / rest;
      share[kVsd] = config.min_share;
    }
    if (calibrate) {
      calibrated = true;
      last_calibration = stats.samples;
    }
  }

  void batch(uint64_t index, uint32_t n) {
    double share[kDists];
    shares(share);
    Rng rng(config.seed, 1000 + index);
    // Samples grouped by distribution, so that each distribution's rays are counted exactly.
    std::vector<Vec3> points, dirs;
    std::vector<int32_t> ref_cell;  // REF: the cell each sample belongs to
    uint32_t first_of[kDists], end_of[kDists], want[kDists];
    uint32_t assigned = 0;
    for (int d = 0; d < kDists; ++d) assigned += want[d] = static_cast<uint32_t>(std::floor(share[d] * n));
    want[kVsd] += n - assigned;  // what rounding left over
    // The view space-direction samples last: they also replace the draws that failed (no
    // mutation candidate left, a degenerate two-point pair), so every batch has n samples.
    constexpr int kOrder[kDists] = {kSil, kTpm, kOd, kTp, kVsd};
    uint64_t discovery_rays = 0;  // the silhouette searches' rays
    uint32_t failed = 0;
    struct SilhouetteJob {
      Candidate candidate;
      double u[2] = {0, 0};
      int n = 0;
      Vec3 points[2], dirs[2];
      uint64_t rays = 0;
    };
    std::vector<SilhouetteJob> sil_jobs;
    for (int d : kOrder) {
      first_of[d] = static_cast<uint32_t>(points.size());
      const uint32_t target = want[d] + (d == kVsd ? failed : 0);
      for (uint32_t k = 0; k < target; ++k) {
        Vec3 p, dir;
        if (config.method == AgvsMethod::kRef) {
          // A random cell, a uniform point in it (rejection in its bounds), a random direction.
          const uint32_t c = static_cast<uint32_t>(rng.below(cells.cell_count()));
          const Box3& b = cells.cell_bounds(c);
          for (int tries = 0; tries < 1000; ++tries) {
            p = {rng.uniform(b.lo.x, b.hi.x), rng.uniform(b.lo.y, b.hi.y), rng.uniform(b.lo.z, b.hi.z)};
            if (cells.cell_at(p) == static_cast<int32_t>(c)) break;
          }
          dir = sphere_direction(rng.uniform(), rng.uniform());
          ref_cell.push_back(static_cast<int32_t>(c));
        } else if (d == kSil) {
          // Candidates and random numbers drawn here, in order; the searches run below.
          if (silhouette.empty()) {
            ++failed;
            continue;
          }
          SilhouetteJob job;
          job.candidate = silhouette.take();
          job.u[0] = rng.uniform(), job.u[1] = rng.uniform();
          sil_jobs.push_back(job);
          continue;
        } else if (!draw(d, rng, p, dir)) {
          ++failed;
          continue;
        }
        points.push_back(p);
        dirs.push_back(dir);
      }
      if (d == kSil && !sil_jobs.empty()) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, sil_jobs.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t j = r.begin(); j < r.end(); ++j) {
            SilhouetteJob& job = sil_jobs[j];
            job.n = silhouette_samples(job.candidate, job.u, job.points, job.dirs, job.rays);
          }
        });
        for (const SilhouetteJob& job : sil_jobs) {
          discovery_rays += job.rays;
          if (job.n == 0) ++failed;
          for (int j = 0; j < job.n; ++j) {
            points.push_back(job.points[j]);
            dirs.push_back(job.dirs[j]);
          }
        }
      }
      end_of[d] = static_cast<uint32_t>(points.size());
    }
    const size_t count = points.size();

    // Cast in fixed chunks within each distribution, in parallel; outputs in sample order.
    constexpr uint32_t kChunk = 1024;
    struct Chunk {
      uint32_t first = 0, size = 0;
      int dist = 0;
      SegmentSet segs;
      std::vector<uint32_t> sample_of;
      uint64_t rays = 0;
    };
    std::vector<Chunk> chunks;
    for (int d : kOrder)
      for (uint32_t f = first_of[d]; f < end_of[d]; f += kChunk) {
        Chunk c;
        c.first = f;
        c.size = std::min(kChunk, end_of[d] - f);
        c.dist = d;
        chunks.push_back(std::move(c));
      }
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) {
      Chunk& c = chunks[k];
      c.rays = caster().cast(std::span<const Vec3>(points.data() + c.first, c.size),
                           std::span<const Vec3>(dirs.data() + c.first, c.size), c.segs, c.sample_of);
    });
    // The cells of every segment, in parallel.
    std::vector<std::vector<int32_t>> seg_cells;
    std::vector<size_t> chunk_start(chunks.size() + 1, 0);
    for (size_t k = 0; k < chunks.size(); ++k) chunk_start[k + 1] = chunk_start[k] + chunks[k].segs.size();
    seg_cells.resize(chunk_start.back());
    if (config.method != AgvsMethod::kRef) {
      tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) {
        std::vector<std::tuple<int32_t, double, double>> stack;
        std::vector<int32_t> leaves;
        const SegmentSet& s = chunks[k].segs;
        for (size_t i = 0; i < s.size(); ++i) cells.cells_of_segment(s.a(i), s.b(i), seg_cells[chunk_start[k] + i], stack, leaves);
      });
    }
    // Apply in sample order (serial: contributions depend on what came before).
    uint64_t dist_contribution[kDists] = {}, dist_rays[kDists] = {};
    dist_rays[kSil] += discovery_rays;
    uint64_t vsd_rays = 0, vsd_contributing = 0;
    // The estimator's camera rays per sample (0 when the sample's point is inside a solid: no
    // camera stands there) and those that were wrong pixels (an entry new to the point's cell).
    std::vector<uint8_t> camera_rays(count, 0), wrong_rays(count, 0), has_segment(count, 0);
    std::vector<int32_t> origin_cell(count, -2);
    for (size_t k = 0; k < chunks.size(); ++k) {
      const Chunk& c = chunks[k];
      dist_rays[c.dist] += c.rays;
      for (size_t i = 0; i < c.segs.size(); ++i) {
        const uint32_t sample = c.first + c.sample_of[i];
        has_segment[sample] = 1;
        const uint32_t objs[2] = {c.segs.object_a[i], c.segs.object_b[i]};
        bool contributed[2] = {false, false};
        uint64_t gain = 0;
        // Whether the sample's point lies on this segment: its own segment (re-casts of points
        // inside solids start elsewhere; see-through companions are the first one's).
        auto on_segment = [&] {
          const Vec3 a = c.segs.a(i), ab = c.segs.b(i) - a;
          const double t = dot(points[sample] - a, ab);
          return t >= 0 && t <= dot(ab, ab);
        };
        if (config.method == AgvsMethod::kRef) {
          // Per cell: the object hit forward from the sample's point, for its cell only; one
          // camera ray, counted once per sample.
          const uint32_t o = objs[1];
          if (camera_rays[sample] == 0 && on_segment()) {
            camera_rays[sample] = 1;
            if (config.filter_statistics) count_hits(ref_cell[sample], o, kNoObject);
            if (o != kNoObject && pvs.insert(static_cast<uint32_t>(ref_cell[sample]), o)) {
              ++gain;
              wrong_rays[sample] = 1;
            }
          }
        } else {
          const bool own = c.dist == kVsd && camera_rays[sample] == 0 && on_segment();
          if (own && origin_cell[sample] == -2) origin_cell[sample] = cells.cell_at(points[sample]);
          bool at_origin[2] = {false, false};
          const std::vector<int32_t>& pierced = seg_cells[chunk_start[k] + i];
          gain = contribute(pvs, pierced, objs[0], objs[1], contributed, own ? origin_cell[sample] : -1, at_origin);
          if (config.filter_statistics)
            for (int32_t cell : pierced) count_hits(cell, objs[0], objs[1]);
          // The estimator's rays: a camera at the point sees along both rays of its segment.
          if (own) {
            camera_rays[sample] = 2;
            wrong_rays[sample] = static_cast<uint8_t>(at_origin[0] + at_origin[1]);
          }
        }
        dist_contribution[c.dist] += gain;
        if (gain > 0 && config.method == AgvsMethod::kAgvs) {
          // A mutation candidate per end whose object contributed.
          const Vec3 a = c.segs.a(i), b = c.segs.b(i);
          for (int e = 0; e < 2; ++e) {
            if (!contributed[e]) continue;
            const Vec3& term = e ? b : a;
            const Vec3& origin = e ? a : b;
            add_candidate({origin, term, end_radius(objs[1 - e], origin), end_radius(objs[e], term), objs[e]});
          }
        }
      }
    }
    // The estimator counts view space-direction samples (all of them for SGVS and REF).
    for (uint32_t s = first_of[kVsd]; s < end_of[kVsd]; ++s) {
      // No segment at all: both rays left the scene without a hit (the caster emits nothing
      // then), so the point is free and its camera sees nothing there: right pixels.
      if (!has_segment[s]) camera_rays[s] = config.method == AgvsMethod::kRef ? 1 : 2;
      vsd_rays += camera_rays[s];
      vsd_contributing += wrong_rays[s];
    }
    // Weights for the next batch: contribution per ray, over the recent batches (each batch
    // counts half as much as the one after it: small contributions are noisy).
    for (int d = 0; d < kDists; ++d) {
      recent_contribution[d] = 0.5 * recent_contribution[d] + static_cast<double>(dist_contribution[d]);
      recent_rays[d] = 0.5 * recent_rays[d] + static_cast<double>(dist_rays[d]);
      weight[d] = recent_rays[d] > 0 ? recent_contribution[d] / recent_rays[d] : 0.0;
      stats.dist_samples[d] += end_of[d] - first_of[d];
      stats.dist_rays[d] += dist_rays[d];
      stats.dist_contribution[d] += dist_contribution[d];
      stats.dist_probability[d] = share[d];
      stats.rays += dist_rays[d];
    }
    stats.samples += count;
    stats.batches += 1;
    stats.mutation_candidates = two_point.size();
    stats.camera_rays += vsd_rays;
    stats.wrong_camera_rays += vsd_contributing;
    update_estimate(vsd_rays, vsd_contributing);
  }

  /// Equation 5: the window holds the most recent batches whose camera rays (view
  /// space-direction rays from free space) number at least (1 - e) / (k^2 e (1 - P)), e the
  /// wrong share over them.
  void update_estimate(uint64_t rays, uint64_t wrong) {
    window.emplace_front(rays, wrong);
    window_total += rays;
    evaluate_window();
  }

  /// The window reaches back at most over the newer half of all camera rays so far: an
  /// estimate must describe the current solution, and the error keeps falling. If even that
  /// half holds too few wrong rays for equation 5 (the error is below what it resolves), there
  /// is no estimate, and error_bound gives the one-sided 90% Poisson upper bound over it.
  void evaluate_window() {
    const uint64_t reach = std::max<uint64_t>(window_total / 2, 1);
    uint64_t n = 0, nc = 0;
    size_t used = 0;
    error = error_bound = std::numeric_limits<double>::quiet_NaN();
    stats.window_rays = 0;
    for (const auto& [r, c] : window) {
      if (used > 0 && n + r > reach) break;
      n += r;
      nc += c;
      ++used;
      if (nc == 0) continue;  // e = 0 would need an infinite window
      const double e = static_cast<double>(nc) / static_cast<double>(n);
      const double need = (1 - e) / (config.window_k * config.window_k * e * (1 - config.window_p));
      if (static_cast<double>(n) >= need) {
        error = config.resolution * e;
        stats.window_rays = n;
        break;
      }
    }
    if (std::isnan(error) && n > 0) {
      // Wilson-Hilferty: the 90% upper bound of a Poisson mean with nc events.
      const double k1 = static_cast<double>(nc) + 1, z = 1.2816;
      const double upper = k1 * std::pow(1 - 1 / (9 * k1) + z / (3 * std::sqrt(k1)), 3);
      error_bound = config.resolution * upper / static_cast<double>(n);
      stats.window_rays = n;
    }
    // Batches beyond the newer half never come back into reach: a new batch moves every older
    // one further back by all its rays, the half's start by only half of them.
    size_t keep = 0;
    for (uint64_t acc = 0; keep < window.size() && (keep == 0 || acc + window[keep].first <= reach); ++keep)
      acc += window[keep].first;
    window.resize(keep);
  }

  double mean_pvs() const { return static_cast<double>(pvs.entries()) / cells.cell_count(); }

  AgvsEditStats edit(const Scene& edited, const RayCaster& rc, const std::vector<uint32_t>& new_of_old) {
    const uint32_t old_n = pvs.object_count(), new_n = static_cast<uint32_t>(edited.object_count());
    if (new_of_old.size() != old_n)
      throw Error("the edit maps " + std::to_string(new_of_old.size()) + " objects, the solution has " +
                  std::to_string(old_n));
    AgvsEditStats st;
    std::vector<char> kept(new_n, 0);
    for (uint32_t m : new_of_old) {
      if (m == kNoObject) {
        ++st.deleted;
        continue;
      }
      if (m >= new_n || kept[m]) throw Error("the edit's object map is not one-to-one");
      kept[m] = 1;
    }
    std::vector<uint32_t> inserted;
    for (uint32_t o = 0; o < new_n; ++o)
      if (!kept[o]) inserted.push_back(o);
    st.inserted = static_cast<uint32_t>(inserted.size());
    // The solution over the new objects, without the deleted ones.
    GlobalPvs next(cells.cell_count(), new_n);
    std::vector<uint16_t> next_hits;
    if (config.filter_statistics) next_hits.assign(size_t(cells.cell_count()) * new_n, 0);
    for (uint32_t c = 0; c < cells.cell_count(); ++c) {
      for (uint32_t o : pvs.list(c)) {
        if (new_of_old[o] == kNoObject) ++st.removed_deleted;
        else next.insert(c, new_of_old[o]);
      }
      if (config.filter_statistics)
        for (uint32_t o = 0; o < old_n; ++o)
          if (new_of_old[o] != kNoObject)
            next_hits[size_t(c) * new_n + new_of_old[o]] = hit_counts[size_t(c) * old_n + o];
    }
    // Inserted objects: what they may hide from each cell leaves its PVS.
    const Scene& sc = edited;
    Box3 all = sc.bounds;
    all.extend(cells.view_box());
    const double reach = all.diagonal();
    std::vector<std::vector<Vec3>> vertices_of(new_n);
    for (uint32_t t = 0; t < sc.triangles.size(); ++t)
      if (!kept[sc.triangle_object[t]])
        for (uint32_t v : sc.triangles[t]) vertices_of[sc.triangle_object[t]].push_back(sc.vertices[v]);
    for (uint32_t o : inserted) {
      if (vertices_of[o].empty() || !sc.objects[o].occluder) continue;  // hides nothing
      const std::vector<Vec3> hull = convex_hull_vertices(vertices_of[o]);
      std::vector<std::vector<uint32_t>> removed(cells.cell_count());
      std::vector<char> cleared(cells.cell_count(), 0);
      tbb::parallel_for(uint32_t{0}, cells.cell_count(), [&](uint32_t c) {
        const ConvexRegion shadow = penumbra(hull, cells.cell_bounds(c), reach);
        cleared[c] = shadow.is_everything();
        for (uint32_t e : next.list(c))
          if (shadow.may_intersect(sc.objects[e].bounds)) removed[c].push_back(e);
      });
      for (uint32_t c = 0; c < cells.cell_count(); ++c) {
        st.cells_cleared += cleared[c];
        for (uint32_t e : removed[c]) st.removed_penumbra += next.erase(c, e);
      }
    }
    // Everything is computed: commit (bind changes nothing when it throws).
    bind(edited, rc);
    pvs = std::move(next);
    hit_counts = std::move(next_hits);
    // Mutation candidates keep their segments; their objects follow the map.
    for (CandidateBuffer* b : {&two_point, &silhouette})
      for (auto& [id, cand] : b->candidates)
        if (cand.object != kNoObject) cand.object = new_of_old[cand.object];
    // The estimator's rays described the old scene.
    window.clear();
    window_total = 0;
    evaluate_window();
    return st;
  }

  std::vector<std::vector<uint32_t>> filtered(const VisibilityFilter& f) const {
    const uint32_t n_cells = cells.cell_count(), n_obj = pvs.object_count();
    if (f.object_space && !config.filter_statistics)
      throw Error("the object space filter needs the sampling densities (AgvsConfig::filter_statistics)");
    if (!(f.k >= 0) || !std::isfinite(f.k)) throw Error("the filter factor k must be finite and >= 0");
    const Scene& sc = scene();
    std::vector<std::vector<uint32_t>> out(n_cells);
    std::vector<std::pair<Box3, uint32_t>> boxes;
    for (uint32_t o = 0; o < n_obj; ++o)
      if (sc.objects[o].rendered && sc.objects[o].triangle_count > 0) boxes.emplace_back(sc.objects[o].bounds, o);
    const BoxTree tree(std::move(boxes));
    tbb::parallel_for(uint32_t{0}, n_cells, [&](uint32_t c) {
      std::vector<uint32_t> list = pvs.list(c);
      if (f.object_space) {
        const double n_v = static_cast<double>(cell_samples[c]);
        const Box3& cb = cells.cell_bounds(c);
        std::vector<uint32_t> found;
        for (uint32_t o : list) {
          const Box3& ob = sc.objects[o].bounds;
          const double hits = hit_counts[size_t(c) * n_obj + o];
          const double e_g = n_v > 0 ? 2 * box_distance(cb, ob) / std::sqrt(n_v) : 0.0;
          const double e_l = hits > 0 ? object_radius[o] / std::sqrt(hits) : e_g;
          const double e = f.k * std::min(e_g, e_l);
          tree.query(Box3(ob.lo - Vec3{e, e, e}, ob.hi + Vec3{e, e, e}), found);
        }
        list.insert(list.end(), found.begin(), found.end());
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
      }
      out[c] = std::move(list);
    });
    if (f.view_neighbours > 0) {
      // Merge with the most similar neighbours (by the object space result, Jaccard).
      const auto near = cells.neighbours();
      std::vector<std::vector<uint32_t>> merged(n_cells);
      tbb::parallel_for(uint32_t{0}, n_cells, [&](uint32_t c) {
        std::vector<std::pair<double, uint32_t>> ranked;
        for (uint32_t nb : near[c]) {
          std::vector<uint32_t> common;
          std::set_intersection(out[c].begin(), out[c].end(), out[nb].begin(), out[nb].end(), std::back_inserter(common));
          const double uni = static_cast<double>(out[c].size() + out[nb].size() - common.size());
          ranked.emplace_back(uni > 0 ? -static_cast<double>(common.size()) / uni : 0.0, nb);  // most similar first
        }
        std::sort(ranked.begin(), ranked.end());
        std::vector<uint32_t> list = out[c];
        for (size_t k = 0; k < ranked.size() && k < f.view_neighbours; ++k)
          list.insert(list.end(), out[ranked[k].second].begin(), out[ranked[k].second].end());
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        merged[c] = std::move(list);
      });
      out = std::move(merged);
    }
    return out;
  }
};

PixelErrorMeasure measure_pixel_error(const Scene& scene, const RayCaster& caster, const CellLocator& cells,
                                      const GlobalPvs& pvs, uint32_t cameras, uint32_t width, uint32_t height,
                                      double fov_degrees, uint64_t seed, bool skip_inside_solids,
                                      uint32_t resolution) {
  if (cameras == 0 || width == 0 || height == 0) throw Error("the pixel error needs cameras and pixels");
  if (!(fov_degrees > 0 && fov_degrees < 180)) throw Error("the field of view must be between 0 and 180 degrees");
  Rng rng(seed, 77);
  const Box3& box = cells.view_box();
  const double f = std::tan(0.5 * fov_degrees * std::numbers::pi / 180.0);
  // The cameras first, serially (reproducible); then rendered in parallel. Wrong pixels come
  // in clusters (a camera that sees a missing object sees it over many pixels), so many
  // small cameras measure better than a few large ones for the same number of rays.
  struct Camera {
    Vec3 eye, forward, right, up;
    int32_t cell = -1;
  };
  std::vector<Camera> cams(cameras);
  for (Camera& cam : cams) {
    for (int tries = 0;; ++tries) {
      if (tries > 100000) throw Error("no camera position found outside the solids");
      cam.eye = {rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y), rng.uniform(box.lo.z, box.hi.z)};
      cam.cell = cells.cell_at(cam.eye);
      if (cam.cell < 0) continue;
      if (!skip_inside_solids) break;
      const Hit probe = caster.intersect(Ray{cam.eye, sphere_direction(rng.uniform(), rng.uniform())});
      if (!probe.hit() || probe.front) break;  // a back face first: the eye is inside a solid
    }
    cam.forward = sphere_direction(rng.uniform(), rng.uniform());
    Vec3 right, up;
    orthonormal_basis(cam.forward, right, up);
    const double roll = 2 * std::numbers::pi * rng.uniform();  // random orientation about the view axis
    cam.right = right * std::cos(roll) + up * std::sin(roll);
    cam.up = cross(cam.right, cam.forward) * -1.0;
  }
  const double aspect = static_cast<double>(height) / width;
  std::vector<uint64_t> wrong_of(cameras, 0);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cameras, 1), [&](const tbb::blocked_range<uint32_t>& range) {
    std::vector<Ray> rays(size_t(width) * height);
    std::vector<Hit> hits(rays.size());
    for (uint32_t k = range.begin(); k < range.end(); ++k) {
      const Camera& cam = cams[k];
      for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x) {
          const double sx = (2 * (x + 0.5) / width - 1) * f, sy = (2 * (y + 0.5) / height - 1) * f * aspect;
          rays[size_t(y) * width + x] = Ray{cam.eye, normalize(cam.forward + cam.right * sx + cam.up * sy)};
        }
      // Large images: in slices, so that one camera also uses every core.
      tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        caster.intersect(std::span<const Ray>(rays.data() + r.begin(), r.size()),
                         std::span<Hit>(hits.data() + r.begin(), r.size()));
      });
      for (const Hit& h : hits)
        if (h.hit() && scene.objects[h.object].rendered && !pvs.contains(static_cast<uint32_t>(cam.cell), h.object))
          ++wrong_of[k];
    }
  });
  PixelErrorMeasure out;
  out.cameras = cameras;
  const uint64_t wrong = std::accumulate(wrong_of.begin(), wrong_of.end(), uint64_t{0});
  const uint64_t pixels = uint64_t{cameras} * width * height;
  for (uint64_t w : wrong_of) out.cameras_wrong += w > 0;
  out.share = static_cast<double>(wrong) / static_cast<double>(pixels);
  out.pixels = out.share * resolution;
  return out;
}

AgvsSolver::AgvsSolver(const Scene& scene, const RayCaster& caster, const CellLocator& cells, const AgvsConfig& config) {
  if (config.batch_size == 0) throw Error("the batch size must be positive");
  if (!(config.min_share >= 0 && config.min_share <= 1)) throw Error("the minimum share must be within [0, 1]");
  if (!(config.window_p > 0 && config.window_p < 1) || !(config.window_k > 0))
    throw Error("the pixel error window needs 0 < P < 1 and k > 0");
  if (scene.object_count() == 0) throw Error("cannot sample an empty scene");
  impl_ = std::make_unique<Impl>(scene, caster, cells, config);
}

AgvsSolver::~AgvsSolver() = default;

void AgvsSolver::set_limits(uint64_t max_samples, double max_seconds, double pixel_error) {
  impl_->config.max_samples = max_samples;
  impl_->config.max_seconds = max_seconds;
  impl_->config.pixel_error = pixel_error;
}

void AgvsSolver::run() {
  Impl& m = *impl_;
  const AgvsConfig& c = m.config;
  if (!c.max_samples && !(c.max_seconds > 0) && !(c.pixel_error > 0))
    throw Error("the PVS computation needs a limit: samples, seconds or a pixel error");
  const auto start = std::chrono::steady_clock::now();
  const double before = m.stats.seconds;
  // The limits count from the start of the computation (a resumed state included) and are
  // checked between batches, so that where a run stops never changes the batches: a run
  // resumed from a state continues exactly as an uninterrupted one.
  // The bar follows the samples, else the time; with only a pixel error to reach, a counter.
  // Its status line shows the mean PVS and the pixel error estimate (or bound).
  const bool by_samples = c.max_samples > 0, by_time = !by_samples && c.max_seconds > 0;
  const bool show = c.show_progress && (!by_samples || c.max_samples > m.stats.samples);
  std::optional<Progress> progress;
  const uint64_t start_ms = static_cast<uint64_t>(before * 1000);
  if (show)
    progress.emplace("pvs", by_samples ? c.max_samples - m.stats.samples
                            : by_time  ? static_cast<uint64_t>(std::max(0.0, c.max_seconds - before) * 1000)
                                       : 0);
  uint64_t shown_ms = start_ms;
  while (true) {
    const double seconds = before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (c.max_samples && m.stats.samples >= c.max_samples) {
      m.stats.stop_reason = "reached " + std::to_string(c.max_samples) + " samples";
      break;
    }
    if (c.max_seconds > 0 && seconds >= c.max_seconds) {
      m.stats.stop_reason = "reached the time limit";
      break;
    }
    if (c.pixel_error > 0 && !std::isnan(m.error) && m.error <= c.pixel_error) {
      char text[96];
      std::snprintf(text, sizeof text, "estimated pixel error at most %g", c.pixel_error);
      m.stats.stop_reason = text;
      break;
    }
    if (c.pixel_error > 0 && !std::isnan(m.error_bound) && m.error_bound <= c.pixel_error) {
      char text[96];
      std::snprintf(text, sizeof text, "pixel error below %g with probability 0.9", c.pixel_error);
      m.stats.stop_reason = text;
      break;
    }
    const uint64_t done = m.stats.samples;
    m.batch(m.stats.batches, c.batch_size);
    if (show) {
      char status[160];
      if (!std::isnan(m.error))
        std::snprintf(status, sizeof status, "mean PVS %.1f, pixel error ~%.2f", m.mean_pvs(), m.error);
      else if (!std::isnan(m.error_bound))
        std::snprintf(status, sizeof status, "mean PVS %.1f, pixel error < %.2f", m.mean_pvs(), m.error_bound);
      else
        std::snprintf(status, sizeof status, "mean PVS %.1f", m.mean_pvs());
      progress->set_status(status);
      if (by_time) {
        const uint64_t now_ms = static_cast<uint64_t>(
            (before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()) * 1000);
        progress->advance(now_ms - shown_ms);
        shown_ms = now_ms;
      } else {
        progress->advance(m.stats.samples - done);
      }
    }
    m.stats.seconds = before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    AgvsPoint point{m.stats.seconds, m.stats.samples, m.stats.rays, m.mean_pvs(), m.error, m.error_bound,
                    m.stats.camera_rays, m.stats.wrong_camera_rays};
    for (size_t k = 0; k < m.references.size(); ++k) point.covered[k] = m.pvs.common_entries(m.references[k]);
    m.stats.curve.push_back(point);
  }
  if (show) progress->finish();
}

namespace {
constexpr char kStateMagic[5] = "VAGS";
constexpr uint32_t kStateVersion = 3;
}  // namespace

void GlobalPvs::save(ByteWriter& w) const {
  w.put(cells_);
  w.put(objects_);
  w.put_array(bits_);
}

GlobalPvs GlobalPvs::load(ByteReader& r, uint32_t cells, uint32_t objects) {
  const uint32_t file_cells = r.get<uint32_t>();
  const uint32_t file_objects = r.get<uint32_t>();
  if (file_cells != cells || file_objects != objects) r.fail("the PVS table does not match the cells and objects");
  GlobalPvs p(cells, objects);
  std::vector<uint64_t> bits;
  r.get_array(bits, p.bits_.size());
  if (bits.size() != p.bits_.size()) r.fail("PVS rows of the wrong size");
  p.bits_ = std::move(bits);
  for (uint32_t c = 0; c < p.cells_; ++c) {
    uint32_t n = 0;
    for (size_t w = 0; w < p.words_; ++w) n += static_cast<uint32_t>(__builtin_popcountll(p.bits_[c * p.words_ + w]));
    if (p.words_ && p.objects_ % 64 && (p.bits_[c * p.words_ + p.words_ - 1] >> (p.objects_ % 64)))
      r.fail("PVS names objects that do not exist");
    p.sizes_[c] = n;
    p.entries_ += n;
  }
  return p;
}

void AgvsSolver::save(const std::string& path, uint64_t identity) const {
  const Impl& m = *impl_;
  ByteWriter w;
  w.put(identity);
  w.put(static_cast<int32_t>(m.config.method));
  w.put(m.config.seed);
  w.put(m.config.batch_size);
  w.put(m.config.min_share);
  m.pvs.save(w);
  const AgvsStats& s = m.stats;
  w.put(s.samples), w.put(s.rays), w.put(s.batches), w.put(s.seconds), w.put(s.window_rays);
  w.put(s.camera_rays), w.put(s.wrong_camera_rays);
  for (int d = 0; d < kDists; ++d) {
    w.put(s.dist_samples[d]), w.put(s.dist_rays[d]), w.put(s.dist_contribution[d]), w.put(s.dist_probability[d]);
    w.put(m.halton_index[d]), w.put(m.weight[d]), w.put(m.recent_contribution[d]), w.put(m.recent_rays[d]);
  }
  w.put(m.last_calibration);
  w.put(static_cast<uint8_t>(m.calibrated));
  w.put(m.error);
  m.two_point.save(w);
  m.silhouette.save(w);
  w.put(m.window_total);
  w.put<uint64_t>(m.window.size());
  for (const auto& [n, nc] : m.window) w.put(n), w.put(nc);
  w.put<uint64_t>(s.curve.size());
  for (const AgvsPoint& p : s.curve) w.put(p);
  w.put(static_cast<uint8_t>(m.config.filter_statistics));
  if (m.config.filter_statistics) {
    w.put_array(m.cell_samples);
    w.put_array(m.hit_counts);
  }
  write_container(path, kStateMagic, kStateVersion, w.data());
}

uint64_t AgvsSolver::state_identity(const std::string& path) {
  uint32_t version = 0;
  const std::string payload = read_container(path, kStateMagic, kStateVersion, version);
  ByteReader r(payload, path);
  return r.get<uint64_t>();
}

void AgvsSolver::load(const std::string& path, uint64_t identity) {
  Impl& m = *impl_;
  uint32_t version = 0;
  const std::string payload = read_container(path, kStateMagic, kStateVersion, version);
  ByteReader r(payload, path);
  if (r.get<uint64_t>() != identity) throw Error(path, 0, "this state belongs to another scene or other view cells");
  const int32_t method = r.get<int32_t>();
  const uint64_t seed = r.get<uint64_t>();
  const uint32_t batch = r.get<uint32_t>();
  const double min_share = r.get<double>();
  if (method != static_cast<int32_t>(m.config.method) || seed != m.config.seed || batch != m.config.batch_size ||
      min_share != m.config.min_share)
    throw Error(path, 0, "this state was computed with another method, seed, batch size or minimum share");
  // Read everything into locals first: a corrupt file leaves the solver as it was.
  GlobalPvs pvs = GlobalPvs::load(r, m.pvs.cell_count(), m.pvs.object_count());
  AgvsStats s = m.stats;
  s.samples = r.get<uint64_t>(), s.rays = r.get<uint64_t>(), s.batches = r.get<uint64_t>();
  s.seconds = r.get<double>(), s.window_rays = r.get<uint64_t>();
  s.camera_rays = r.get<uint64_t>(), s.wrong_camera_rays = r.get<uint64_t>();
  uint64_t halton[kDists];
  double weight[kDists], recent_c[kDists], recent_r[kDists];
  for (int d = 0; d < kDists; ++d) {
    s.dist_samples[d] = r.get<uint64_t>(), s.dist_rays[d] = r.get<uint64_t>();
    s.dist_contribution[d] = r.get<uint64_t>(), s.dist_probability[d] = r.get<double>();
    halton[d] = r.get<uint64_t>(), weight[d] = r.get<double>(), recent_c[d] = r.get<double>(), recent_r[d] = r.get<double>();
  }
  const uint64_t last_calibration = r.get<uint64_t>();
  const bool calibrated = r.get<uint8_t>() != 0;
  const double error = r.get<double>();
  if (!(s.seconds >= 0 && s.seconds < 1e9)) r.fail("the time spent is out of range");
  for (int d = 0; d < kDists; ++d)
    if (!(weight[d] >= 0 && weight[d] < 1e300) || !(recent_c[d] >= 0 && recent_c[d] < 1e300) ||
        !(recent_r[d] >= 0 && recent_r[d] < 1e300) || !(s.dist_probability[d] >= 0 && s.dist_probability[d] <= 1))
      r.fail("mixture weights out of range");
  // Candidate ends lie in the view box or on the scene; a little slack for rounding.
  Box3 ends = m.cells.view_box();
  ends.extend(m.scene_->bounds.lo);
  ends.extend(m.scene_->bounds.hi);
  const Vec3 slack = ends.extent() * 1e-6 + Vec3{1e-9, 1e-9, 1e-9};
  ends.lo = ends.lo - slack, ends.hi = ends.hi + slack;
  const uint32_t objects = m.pvs.object_count();
  CandidateBuffer two_point = CandidateBuffer::load(r, m.config.mutation_buffer, payload.size(), ends, objects);
  CandidateBuffer silhouette = CandidateBuffer::load(r, m.config.mutation_buffer, payload.size(), ends, objects);
  const uint64_t window_total = r.get<uint64_t>();
  const uint64_t windows = r.get<uint64_t>();
  if (windows > payload.size()) r.fail("estimator window too long");
  std::deque<std::pair<uint64_t, uint64_t>> window;
  for (uint64_t k = 0; k < windows; ++k) {
    const uint64_t n = r.get<uint64_t>(), nc = r.get<uint64_t>();
    window.emplace_back(n, nc);
  }
  const uint64_t points = r.get<uint64_t>();
  if (points > payload.size()) r.fail("curve too long");
  s.curve.clear();
  for (uint64_t k = 0; k < points; ++k) s.curve.push_back(r.get<AgvsPoint>());
  const bool with_filter = r.get<uint8_t>() != 0;
  if (with_filter != m.config.filter_statistics)
    throw Error(path, 0, with_filter ? "this state keeps the visibility filter's statistics: resume with the filter"
                                     : "this state has no visibility filter statistics: resume without the filter");
  std::vector<uint64_t> cell_samples;
  std::vector<uint16_t> hit_counts;
  std::vector<GlobalPvs> references;  ///< for the curve's coverage only
  if (with_filter) {
    r.get_array(cell_samples, m.cell_samples.size());
    r.get_array(hit_counts, m.hit_counts.size());
    if (cell_samples.size() != m.cell_samples.size() || hit_counts.size() != m.hit_counts.size())
      r.fail("filter statistics of the wrong size");
  }
  if (!r.at_end()) r.fail("trailing bytes");
  s.mutation_candidates = two_point.size();
  // Commit.
  m.pvs = std::move(pvs);
  m.stats = std::move(s);
  for (int d = 0; d < kDists; ++d)
    m.halton_index[d] = halton[d], m.weight[d] = weight[d], m.recent_contribution[d] = recent_c[d],
    m.recent_rays[d] = recent_r[d];
  m.last_calibration = last_calibration;
  m.calibrated = calibrated;
  m.error = error;
  m.two_point = std::move(two_point);
  m.silhouette = std::move(silhouette);
  m.window = std::move(window);
  m.window_total = window_total;
  m.cell_samples = std::move(cell_samples);
  m.hit_counts = std::move(hit_counts);
  m.evaluate_window();
}

AgvsEditStats AgvsSolver::edit(const Scene& edited, const RayCaster& caster, const std::vector<uint32_t>& new_of_old) {
  return impl_->edit(edited, caster, new_of_old);
}

std::vector<std::vector<uint32_t>> AgvsSolver::filtered_pvs(const VisibilityFilter& filter) const {
  return impl_->filtered(filter);
}

void AgvsSolver::add_reference(GlobalPvs reference) {
  if (impl_->references.size() >= AgvsPoint::kReferences)
    throw Error("at most " + std::to_string(AgvsPoint::kReferences) + " reference solutions");
  if (reference.cell_count() != impl_->pvs.cell_count() || reference.object_count() != impl_->pvs.object_count())
    throw Error("the reference PVSs are for other view cells or another scene");
  impl_->references.push_back(std::move(reference));
}

const GlobalPvs& AgvsSolver::pvs() const { return impl_->pvs; }
const AgvsStats& AgvsSolver::stats() const { return impl_->stats; }
double AgvsSolver::pixel_error() const { return impl_->error; }
double AgvsSolver::pixel_error_bound() const { return impl_->error_bound; }
double AgvsSolver::mean_pvs() const { return impl_->mean_pvs(); }

}  // namespace viewcells
