/// Proving objects hidden from view cells through a solid BSP's portals (hidden/hidden_space.h;
/// issue 65), and solid space from a mesh scene's convex closed objects (the volumetric
/// occluders of instant-visibility.txt, section 5.3, taken as they are instead of voxelized).
#include "viewcells/hidden/hidden_space.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <tuple>

#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"

namespace viewcells {

namespace {

std::string point_text(const Vec3& p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.x << ", " << p.y << ", " << p.z << ")";
  return s.str();
}

class BspHiddenSpace : public HiddenSpace {
 public:
  BspHiddenSpace(SolidBsp bsp, const Scene& scene, std::string what, const std::vector<Vec3>& inside)
      : graph_(std::move(bsp)), what_(std::move(what)), object_count_(scene.object_count()) {
    place_objects(scene);
    const SolidBsp& b = graph_.bsp();
    empty_leaves_ = static_cast<size_t>(std::count(b.leaf_solid.begin(), b.leaf_solid.end(), 0));
    find_leak(inside);
  }

  std::string describe() const override {
    std::ostringstream s;
    s << what_ << ": " << empty_leaves_ << " empty of " << graph_.bsp().leaf_count() << " leaves, "
      << graph_.portal_count() / 2 << " portals";
    if (unplaced_) s << ", " << unplaced_ << " objects in no empty leaf";
    return s.str();
  }
  std::vector<std::string> warnings() const override { return warnings_; }
  bool leaks() const override { return leaks_; }
  bool solid_at(const Vec3& p) const override {
    const SolidBsp& b = graph_.bsp();
    return b.leaf_solid[static_cast<size_t>(b.leaf_at(p))] != 0;
  }

  HiddenProof prove(const std::vector<std::vector<Polytope>>& cells, uint64_t max_steps,
                    const Deadline& deadline) const override {
    const auto t0 = std::chrono::steady_clock::now();
    HiddenProof out;
    out.unhidden.resize(cells.size());
    std::vector<PortalGraph::FloodStats> stats(cells.size());
    std::vector<uint64_t> floods(cells.size(), 0);
    std::vector<uint8_t> unproven(cells.size(), 0);
    Progress progress("proving hidden objects", cells.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      PortalGraph::FloodState state;
      std::vector<std::pair<int32_t, Polytope>> parts;
      for (size_t c = r.begin(); c < r.end(); ++c) {
        throw_if_interrupted("proving hidden objects");
        if (deadline.passed()) {  // out of time: this cell proves nothing
          unproven[c] = 1;
          out.unhidden[c].resize(object_count_);
          for (uint32_t o = 0; o < object_count_; ++o) out.unhidden[c][o] = o;
          continue;
        }
        graph_.reset(state);
        parts.clear();
        for (const Polytope& piece : cells[c]) graph_.split_to_leaves(piece, parts);
        for (const auto& [leaf, part] : parts) {
          graph_.flood(part, leaf, state, max_steps, stats[c]);
          ++floods[c];
        }
        graph_.finish(state);
        progress.advance();
        auto& list = out.unhidden[c];
        for (uint32_t o = 0; o < object_count_; ++o)
          if (state.object_seen[o]) list.push_back(o);
      }
    });
    progress.finish();
    for (size_t c = 0; c < cells.size(); ++c) {
      out.steps += stats[c].steps;
      out.overflows += stats[c].overflows;
      out.floods += floods[c];
      out.cells_unproven += unproven[c];
    }
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
  }

 private:
  /// Every object's triangles cut into the empty leaves they have area or an edge in.
  void place_objects(const Scene& scene) {
    std::vector<std::vector<uint32_t>> by_object(object_count_);
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) by_object[scene.triangle_object[t]].push_back(t);
    std::vector<std::vector<PortalGraph::Placed>> placed(object_count_);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, object_count_, 1), [&](const tbb::blocked_range<size_t>& r) {
      std::vector<std::pair<int32_t, Winding>> parts;
      for (size_t o = r.begin(); o < r.end(); ++o) {
        parts.clear();
        for (uint32_t t : by_object[o]) {
          const auto& tri = scene.triangles[t];
          graph_.split_polygon({scene.vertices[tri[0]], scene.vertices[tri[1]], scene.vertices[tri[2]]}, parts);
        }
        for (auto& [leaf, w] : parts) placed[o].push_back({leaf, static_cast<uint32_t>(o), std::move(w)});
      }
    });
    std::vector<PortalGraph::Placed> all;
    for (uint32_t o = 0; o < object_count_; ++o) {
      if (placed[o].empty() && scene.objects[o].triangle_count) ++unplaced_;
      for (auto& p : placed[o]) all.push_back(std::move(p));
    }
    graph_.place(std::move(all), static_cast<uint32_t>(object_count_));
  }

  /// A leak: an empty leaf open to the outer box that portals connect to a point of `inside`.
  void find_leak(const std::vector<Vec3>& inside) {
    const SolidBsp& b = graph_.bsp();
    std::vector<int32_t> from(b.leaf_count(), -2), stack;
    for (const Vec3& p : inside) {
      const int32_t l = b.leaf_at(p);
      if (b.leaf_solid[static_cast<size_t>(l)] || from[static_cast<size_t>(l)] != -2) continue;
      from[static_cast<size_t>(l)] = -1;
      stack.push_back(l);
    }
    while (!stack.empty()) {
      const int32_t l = stack.back();
      stack.pop_back();
      for (uint32_t pi : graph_.leaf_portals(l)) {
        const int32_t to = graph_.portal(pi).to;
        if (from[static_cast<size_t>(to)] != -2) continue;
        from[static_cast<size_t>(to)] = l;
        stack.push_back(to);
      }
    }
    for (int32_t open : graph_.open_leaves()) {
      if (from[static_cast<size_t>(open)] == -2) continue;
      size_t steps = 0;
      for (int32_t l = open; from[static_cast<size_t>(l)] >= 0; l = from[static_cast<size_t>(l)]) ++steps;
      std::ostringstream w;
      w << what_ << " leaks: empty leaf " << open << " near " << point_text(centre_of_leaf(open))
        << " reaches the outer box and is " << steps
        << " portals from where viewers are; lines may leave through it, and the proof keeps all they reach";
      warnings_.push_back(w.str());
      leaks_ = true;
      break;
    }
  }

  Vec3 centre_of_leaf(int32_t leaf) const {
    std::vector<std::pair<int32_t, Polytope>> parts;
    graph_.split_to_leaves(Polytope::box(graph_.bsp().bounds), parts);
    for (const auto& [l, p] : parts)
      if (l == leaf) {
        Box3 b;
        for (const Vec3& v : p.vertices(graph_.tolerance())) b.extend(v);
        return b.center();
      }
    return graph_.bsp().bounds.center();
  }

  PortalGraph graph_;
  std::string what_;
  size_t object_count_ = 0, empty_leaves_ = 0, unplaced_ = 0;
  std::vector<std::string> warnings_;
  bool leaks_ = false;
};

bool same_plane(const HalfPlane& a, const HalfPlane& b, double eps) {
  return dot(a.normal, b.normal) > 1 - 1e-12 && std::abs(a.dist - b.dist) <= eps;
}

}  // namespace

std::shared_ptr<const HiddenSpace> bsp_hidden_space(SolidBsp bsp, const Scene& scene, const std::string& what,
                                                    const std::vector<Vec3>& inside) {
  return std::make_shared<BspHiddenSpace>(std::move(bsp), scene, what, inside);
}

SolidBsp solid_bsp_from_brushes(const std::vector<Brush>& brushes, const Box3& bounds, size_t max_nodes) {
  SolidBsp out;
  out.bounds = bounds;
  const double eps = 1e-7 * std::max(1.0, bounds.diagonal());
  struct Item {
    uint32_t brush;
    uint64_t done;  ///< the brush's planes the region already lies behind
  };
  for (const Brush& b : brushes)
    if (b.planes.empty() || b.planes.size() > 64 || b.vertices.empty())
      throw Error("a brush needs 1 to 64 planes and its vertices");
  auto full = [&brushes](uint32_t b) {
    const size_t n = brushes[b].planes.size();
    return n == 64 ? ~uint64_t{0} : (uint64_t{1} << n) - 1;
  };
  std::function<int32_t(const std::vector<Item>&)> build = [&](const std::vector<Item>& items) -> int32_t {
    for (const Item& it : items)
      if (it.done == full(it.brush)) {
        out.leaf_solid.push_back(1);
        return -static_cast<int32_t>(out.leaf_solid.size());
      }
    if (items.empty()) {
      out.leaf_solid.push_back(0);
      return -static_cast<int32_t>(out.leaf_solid.size());
    }
    if (out.nodes.size() >= max_nodes)
      throw Error("the solid space of " + std::to_string(brushes.size()) + " brushes needs more than " +
                  std::to_string(max_nodes) + " BSP nodes");
    const Item& first = items.front();
    const Brush& fb = brushes[first.brush];
    size_t k = 0;
    while ((first.done >> k) & 1u) ++k;
    const HalfPlane split = fb.planes[k];
    std::vector<Item> front, back;
    for (const Item& it : items) {
      const Brush& b = brushes[it.brush];
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const Vec3& v : b.vertices) {
        const double d = split.distance(v);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      uint64_t f = it.done, bk = it.done;
      for (size_t j = 0; j < b.planes.size(); ++j) {
        if (same_plane(b.planes[j], split, eps)) bk |= uint64_t{1} << j;
        if (same_plane(b.planes[j], HalfPlane{-1.0 * split.normal, -split.dist}, eps)) f |= uint64_t{1} << j;
      }
      if (hi > eps) front.push_back({it.brush, f});
      if (lo < -eps) back.push_back({it.brush, bk});
    }
    const int32_t id = static_cast<int32_t>(out.nodes.size());
    out.planes.push_back(split);
    out.nodes.push_back({static_cast<int32_t>(out.planes.size() - 1), {0, 0}});
    const int32_t f = build(front);
    out.nodes[static_cast<size_t>(id)].children[0] = f;
    const int32_t b = build(back);
    out.nodes[static_cast<size_t>(id)].children[1] = b;
    return id;
  };
  std::vector<Item> all;
  for (uint32_t b = 0; b < brushes.size(); ++b) all.push_back({b, 0});
  const int32_t root = build(all);
  if (root < 0) {  // a single leaf
    out.nodes.clear();
  }
  return out;
}

std::vector<Brush> convex_solid_brushes(const Scene& scene, uint64_t& skipped) {
  skipped = 0;
  std::vector<std::vector<uint32_t>> by_object(scene.object_count());
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) by_object[scene.triangle_object[t]].push_back(t);
  const double eps = 1e-7 * std::max(1.0, scene.bounds.diagonal());
  std::vector<Brush> out;
  for (size_t o = 0; o < scene.object_count(); ++o) {
    const ObjectInfo& info = scene.objects[o];
    if (!info.triangle_count) continue;
    if (!info.solid() || !info.occluder) {
      ++skipped;
      continue;
    }
    Brush b;
    for (uint32_t t : by_object[o])
      for (uint32_t v : scene.triangles[t]) b.vertices.push_back(scene.vertices[v]);
    std::sort(b.vertices.begin(), b.vertices.end(),
              [](const Vec3& a, const Vec3& c) { return std::tie(a.x, a.y, a.z) < std::tie(c.x, c.y, c.z); });
    b.vertices.erase(std::unique(b.vertices.begin(), b.vertices.end(),
                                 [](const Vec3& a, const Vec3& c) { return a.x == c.x && a.y == c.y && a.z == c.z; }),
                     b.vertices.end());
    bool ok = true;
    for (uint32_t t : by_object[o]) {
      const Vec3 n = scene.triangle_normal(t);
      const double len = length(n);
      if (!(len > 0)) continue;
      const HalfPlane h{n / len, dot(n / len, scene.vertices[scene.triangles[t][0]])};
      if (std::any_of(b.planes.begin(), b.planes.end(), [&](const HalfPlane& p) { return same_plane(p, h, eps); }))
        continue;
      for (const Vec3& v : b.vertices)
        if (h.distance(v) > 1e3 * eps) ok = false;  // not convex
      b.planes.push_back(h);
      if (!ok || b.planes.size() > 64) break;
    }
    if (!ok || b.planes.size() > 64 || b.planes.size() < 4) {
      ++skipped;
      continue;
    }
    out.push_back(std::move(b));
  }
  return out;
}

std::shared_ptr<const HiddenSpace> solid_objects_hidden_space(const Scene& scene, std::string& why) {
  uint64_t skipped = 0;
  std::vector<Brush> brushes = convex_solid_brushes(scene, skipped);
  if (brushes.empty()) {
    why = "no object is a closed, convex solid that stops rays (" + std::to_string(skipped) +
          " objects are not), so nothing can be proven hidden";
    return nullptr;
  }
  Box3 bounds = scene.bounds;
  const double margin = 0.01 * bounds.diagonal() + 1;
  bounds.lo = bounds.lo - Vec3{margin, margin, margin};
  bounds.hi = bounds.hi + Vec3{margin, margin, margin};
  SolidBsp bsp;
  try {
    bsp = solid_bsp_from_brushes(brushes, bounds);
  } catch (const Error& e) {
    why = e.what();
    return nullptr;
  }
  why.clear();
  return bsp_hidden_space(std::move(bsp),
                          scene,
                          std::to_string(brushes.size()) + " convex solids of the scene (" + std::to_string(skipped) +
                              " other objects see-through for the proof)",
                          {});
}

}  // namespace viewcells
