/// Portals between the empty leaves of a solid BSP and the conservative flood through them
/// (hidden/portals.h; issue 65). The portal of a node is its plane's polygon inside the node's
/// region, pushed down both subtrees; the flood is a map compiler's recursive portal flow
/// (Teller's antipenumbra approximated by separating planes through an edge of one polygon and
/// a vertex of the other), with a convex polytope as its source instead of a portal.
#include "viewcells/hidden/portals.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <set>
#include <tuple>

#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"

namespace viewcells {

namespace {

HalfPlane flipped(const HalfPlane& h) { return {-1.0 * h.normal, -h.dist}; }

/// clip_winding, also collecting the points where the plane cuts the polygon's edges.
Winding clip_collect(const Winding& w, const HalfPlane& plane, double slack, std::vector<Vec3>* cut) {
  const size_t n = w.size();
  if (n == 0) return {};
  double s_small[16];
  std::vector<double> s_big;
  double* s = s_small;
  if (n > 16) {
    s_big.resize(n);
    s = s_big.data();
  }
  bool all_in = true, all_out = true;
  for (size_t i = 0; i < n; ++i) {
    s[i] = plane.distance(w[i]) + slack;
    if (s[i] < 0) all_in = false;
    else all_out = false;
  }
  if (all_in) return w;
  if (all_out) return {};
  Winding out;
  out.reserve(n + 2);
  for (size_t i = 0; i < n; ++i) {
    const size_t j = i + 1 == n ? 0 : i + 1;
    if (s[i] >= 0) out.push_back(w[i]);
    if ((s[i] >= 0) != (s[j] >= 0)) {
      const double t = s[i] / (s[i] - s[j]);
      const Vec3 p = w[i] + (w[j] - w[i]) * t;
      out.push_back(p);
      if (cut) cut->push_back(p);
    }
  }
  if (out.size() < 3) return {};
  return out;
}

/// A convex set as vertices and edges (pairs of vertex indices), for separating planes.
struct Convex {
  std::vector<Vec3> v;
  std::vector<std::array<uint32_t, 2>> e;
};

uint32_t welded_index(std::vector<Vec3>& v, const Vec3& p, double weld) {
  for (uint32_t i = 0; i < v.size(); ++i)
    if (std::abs(v[i].x - p.x) <= weld && std::abs(v[i].y - p.y) <= weld && std::abs(v[i].z - p.z) <= weld) return i;
  v.push_back(p);
  return static_cast<uint32_t>(v.size() - 1);
}

Convex convex_of(const Polytope& p, double weld) {
  Convex c;
  std::set<std::array<uint32_t, 2>> edges;
  for (const Winding& f : p.faces) {
    std::vector<uint32_t> ids;
    for (const Vec3& x : f) ids.push_back(welded_index(c.v, x, weld));
    for (size_t i = 0; i < ids.size(); ++i) {
      const uint32_t a = ids[i], b = ids[(i + 1) % ids.size()];
      if (a != b) edges.insert({std::min(a, b), std::max(a, b)});
    }
  }
  c.e.assign(edges.begin(), edges.end());
  return c;
}

Convex convex_of(const Winding& w) {
  Convex c;
  c.v = w;
  for (uint32_t i = 0; i < w.size(); ++i) c.e.push_back({i, static_cast<uint32_t>((i + 1) % w.size())});
  return c;
}

/// Every plane through an edge of one of `a`, `b` and a vertex of the other that has all of `a`
/// behind it and all of `b` in front (a separating plane), oriented so that a line from `a`
/// through `b` meets what lies beyond `b` only in front of each. The same for every target
/// beyond `b`: a flood finds them once per portal sequence, not once per target.
void separators(const Convex& a, const Convex& b, double eps, std::vector<HalfPlane>& out) {
  out.clear();
  for (int pass = 0; pass < 2; ++pass) {
    const Convex& edges = pass == 0 ? a : b;
    const Convex& points = pass == 0 ? b : a;
    for (const auto& e : edges.e) {
      const Vec3 p1 = edges.v[e[0]], d1 = edges.v[e[1]] - p1;
      const double l1 = length(d1);
      if (!(l1 > eps)) continue;
      for (const Vec3& q : points.v) {
        const Vec3 d2 = q - p1;
        Vec3 n = cross(d1, d2);
        const double ln = length(n);
        // Nearly collinear: the plane's direction would be rounding.
        if (!(ln > 1e-7 * l1 * length(d2)) || !(ln > 0)) continue;
        n = n / ln;
        const double d0 = dot(n, p1);
        double amin = std::numeric_limits<double>::infinity(), amax = -amin;
        for (const Vec3& x : a.v) {
          const double s = dot(n, x) - d0;
          amin = std::min(amin, s);
          amax = std::max(amax, s);
        }
        if (amax > eps && amin < -eps) continue;  // a on both sides
        double bmin = std::numeric_limits<double>::infinity(), bmax = -bmin;
        for (const Vec3& x : b.v) {
          const double s = dot(n, x) - d0;
          bmin = std::min(bmin, s);
          bmax = std::max(bmax, s);
        }
        double sign = 0;
        if (amax <= eps && bmin >= -eps && (bmax > eps || amin < -eps)) sign = 1;
        else if (amin >= -eps && bmax <= eps && (bmin < -eps || amax > eps)) sign = -1;
        else continue;
        out.push_back(HalfPlane{n * sign, d0 * sign});
      }
    }
  }
}

/// Clips `t` by `planes` in order; false when nothing of it is left.
bool clip_by(const std::vector<HalfPlane>& planes, Winding& t, double slack) {
  for (const HalfPlane& h : planes) {
    t = clip_collect(t, h, slack, nullptr);
    if (t.empty()) return false;
  }
  return true;
}

inline bool test_bit(const uint64_t* row, size_t i) { return (row[i >> 6] >> (i & 63)) & 1u; }
inline void set_bit(uint64_t* row, size_t i) { row[i >> 6] |= uint64_t{1} << (i & 63); }

}  // namespace

struct FloodRun {
  const PortalGraph& g;
  Convex source;
  PortalGraph::FloodState& st;
  uint64_t max_steps;
  PortalGraph::FloodStats& stats;
  std::vector<uint8_t>& in_chain;
  std::vector<std::vector<uint64_t>> might;  ///< per depth
  /// Per depth, the source's and the pass's separating planes (a deque: deeper levels are
  /// added while shallower ones are in use).
  std::deque<std::vector<HalfPlane>> separating;
  bool overflow = false;
  double eps, slack;
  uint64_t steps = 0;

  void keep_all(const uint64_t* row) {
    for (size_t w = 0; w < g.words_; ++w) {
      st.visible[w] |= row[w];
      st.overflow[w] |= row[w];
    }
  }

  /// Object o seen: the leaves it lies in may be done, and the portals into them.
  void see(uint32_t o) {
    if (st.object_seen[o]) return;
    st.object_seen[o] = 1;
    for (int32_t l : g.object_leaves_[o])
      if (--st.remaining[static_cast<size_t>(l)] == 0)
        for (uint32_t q : g.in_[static_cast<size_t>(l)])
          if (test_bit(st.visible.data(), q)) set_bit(st.done.data(), q);
  }

  void cross(uint32_t q) {
    set_bit(st.visible.data(), q);
    if (st.remaining[static_cast<size_t>(g.portals_[q].to)] == 0) set_bit(st.done.data(), q);
  }

  /// The placed polygons of `leaf` that a line from the source through the pass (in front of
  /// `pass_plane` and of its separating planes `seps`) meets.
  void see_through(const std::vector<HalfPlane>& seps, const HalfPlane& pass_plane, int32_t leaf) {
    if (st.remaining[static_cast<size_t>(leaf)] == 0) return;
    for (const PortalGraph::Placed& p : g.placed_[static_cast<size_t>(leaf)]) {
      if (st.object_seen[p.object]) continue;
      Winding w = clip_collect(p.polygon, pass_plane, slack, nullptr);
      if (!w.empty() && clip_by(seps, w, slack)) see(p.object);
    }
  }

  void recurse(const Winding& pass, const HalfPlane& pass_plane, int32_t leaf, size_t depth) {
    if (separating.size() <= depth) separating.resize(depth + 1);
    std::vector<HalfPlane>& seps = separating[depth];
    separators(source, convex_of(pass), eps, seps);
    see_through(seps, pass_plane, leaf);
    if (might.size() <= depth + 1) might.emplace_back(g.words_);
    const uint64_t* row = might[depth].data();
    for (const uint32_t qi : g.out_[static_cast<size_t>(leaf)]) {
      if (overflow) {
        keep_all(row);
        return;
      }
      if (!test_bit(row, qi)) continue;
      const PortalGraph::Portal& q = g.portals_[qi];
      if (in_chain[static_cast<size_t>(q.to)]) continue;  // a line crosses a convex leaf once
      ++stats.steps;
      if (++steps > max_steps) {
        overflow = true;
        ++stats.overflows;
        keep_all(row);
        return;
      }
      uint64_t* next = might[depth + 1].data();
      const uint64_t* q_might = &g.might_[qi * g.words_];
      bool more = false;
      for (size_t w = 0; w < g.words_; ++w) {
        next[w] = row[w] & q_might[w];
        more = more || (next[w] & ~st.done[w]) != 0;
      }
      if (!more && test_bit(st.done.data(), qi)) continue;  // nothing it could add
      Winding t = clip_collect(q.winding, pass_plane, slack, nullptr);  // beyond the last portal
      if (t.empty() || !clip_by(seps, t, slack)) continue;
      cross(qi);
      in_chain[static_cast<size_t>(q.to)] = 1;
      recurse(t, q.plane, q.to, depth + 1);
      in_chain[static_cast<size_t>(q.to)] = 0;
    }
  }
};

int32_t SolidBsp::leaf_at(const Vec3& p) const {
  if (nodes.empty()) return 0;
  int32_t n = 0;
  for (;;) {
    const Node& node = nodes[static_cast<size_t>(n)];
    const int32_t c = node.children[planes[static_cast<size_t>(node.plane)].distance(p) >= 0 ? 0 : 1];
    if (c < 0) return -(c + 1);
    n = c;
  }
}

Polytope Polytope::box(const Box3& b) {
  auto corner = [&b](int i) { return Vec3{i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z}; };
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  Polytope p;
  for (const auto& f : kFaces) p.faces.push_back({corner(f[0]), corner(f[1]), corner(f[2]), corner(f[3])});
  return p;
}

std::vector<Vec3> Polytope::vertices(double weld) const {
  std::vector<Vec3> v;
  for (const Winding& f : faces)
    for (const Vec3& x : f) welded_index(v, x, weld);
  return v;
}

Winding clip_winding(const Winding& w, const HalfPlane& plane, double slack) {
  return clip_collect(w, plane, slack, nullptr);
}

Polytope clip_polytope(const Polytope& p, const HalfPlane& plane, double slack) {
  Polytope out;
  std::vector<Vec3> cut;
  for (const Winding& f : p.faces) {
    Winding c = clip_collect(f, plane, slack, &cut);
    if (!c.empty()) out.faces.push_back(std::move(c));
  }
  if (out.faces.empty() || cut.size() < 3) return out;
  // The cap: the cut points in order around their centre, in the plane.
  Vec3 centre{0, 0, 0};
  for (const Vec3& x : cut) centre = centre + x;
  centre = centre / static_cast<double>(cut.size());
  Vec3 u, v;
  orthonormal_basis(normalize(plane.normal), u, v);
  std::vector<std::pair<double, Vec3>> around;
  for (const Vec3& x : cut) around.emplace_back(std::atan2(dot(x - centre, v), dot(x - centre, u)), x);
  std::sort(around.begin(), around.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  Winding cap;
  for (const auto& [angle, x] : around)
    if (cap.empty() || length(x - cap.back()) > 1e-12 * (1 + length(x))) cap.push_back(x);
  while (cap.size() > 1 && length(cap.front() - cap.back()) <= 1e-12 * (1 + length(cap.front()))) cap.pop_back();
  if (cap.size() >= 3) out.faces.push_back(std::move(cap));
  return out;
}

PortalGraph::PortalGraph(SolidBsp bsp) : bsp_(std::move(bsp)) {
  if (bsp_.leaf_solid.empty()) throw Error("a solid BSP needs at least one leaf");
  if (bsp_.bounds.empty()) throw Error("a solid BSP needs bounds");
  for (const auto& n : bsp_.nodes)
    for (int32_t c : n.children)
      if ((c >= 0 && static_cast<size_t>(c) >= bsp_.nodes.size()) ||
          (c < 0 && static_cast<size_t>(-(c + 1)) >= bsp_.leaf_solid.size()) || n.plane < 0 ||
          static_cast<size_t>(n.plane) >= bsp_.planes.size())
        throw Error("a solid BSP node names a node, leaf or plane it does not have");
  eps_ = 1e-7 * std::max(1.0, bsp_.bounds.diagonal());
  out_.resize(bsp_.leaf_count());
  in_.resize(bsp_.leaf_count());
  make_portals();
  for (uint32_t i = 0; i < portals_.size(); ++i) in_[static_cast<size_t>(portals_[i].to)].push_back(i);
  place({}, 0);
  make_might_see();
}

namespace {

/// The polygon `w` pushed down the subtree `child` of `bsp`: at_leaf(leaf, part) for every leaf
/// it reaches (a part on a plane goes both ways).
template <class F>
void descend(const SolidBsp& bsp, int32_t child, const Winding& w, double slack, F&& at_leaf) {
  if (child < 0) {
    at_leaf(-(child + 1), w);
    return;
  }
  const SolidBsp::Node& n = bsp.nodes[static_cast<size_t>(child)];
  const HalfPlane& p = bsp.planes[static_cast<size_t>(n.plane)];
  Winding front = clip_collect(w, p, slack, nullptr);
  if (!front.empty()) descend(bsp, n.children[0], front, slack, at_leaf);
  Winding back = clip_collect(w, flipped(p), slack, nullptr);
  if (!back.empty()) descend(bsp, n.children[1], back, slack, at_leaf);
}

/// A polygon of the plane `p` covering `box`.
Winding base_winding(const HalfPlane& p, const Box3& box) {
  const Vec3 n = normalize(p.normal);
  const Vec3 c = box.center();
  const Vec3 o = c - n * (dot(n, c) - p.dist / length(p.normal));
  Vec3 u, v;
  orthonormal_basis(n, u, v);
  const double r = box.diagonal() + 1;
  Winding w{o - u * r - v * r, o + u * r - v * r, o + u * r + v * r, o - u * r + v * r};
  for (int a = 0; a < 3; ++a) {
    Vec3 e{0, 0, 0};
    e[a] = 1;
    w = clip_collect(w, HalfPlane{e, box.lo[a]}, 0, nullptr);
    w = clip_collect(w, HalfPlane{-1.0 * e, -box.hi[a]}, 0, nullptr);
  }
  return w;
}

}  // namespace

void PortalGraph::make_portals() {
  const SolidBsp& b = bsp_;
  std::vector<HalfPlane> path;
  // Depth first, `path` holding the half-spaces of the node's region.
  std::function<void(int32_t)> walk = [&](int32_t node) {
    if (node < 0) return;
    throw_if_interrupted("portals");
    const SolidBsp::Node& n = b.nodes[static_cast<size_t>(node)];
    const HalfPlane& p = b.planes[static_cast<size_t>(n.plane)];
    Winding w = base_winding(p, b.bounds);
    for (const HalfPlane& h : path) {
      if (w.empty()) break;
      w = clip_collect(w, h, eps_, nullptr);
    }
    if (!w.empty())
      descend(b, n.children[0], w, eps_, [&](int32_t front, const Winding& part) {
        if (b.leaf_solid[static_cast<size_t>(front)]) return;
        descend(b, n.children[1], part, eps_, [&](int32_t back, const Winding& piece) {
          if (b.leaf_solid[static_cast<size_t>(back)] || back == front) return;
          const uint32_t id = static_cast<uint32_t>(portals_.size());
          const double len = length(p.normal);
          const HalfPlane unit{p.normal / len, p.dist / len};
          portals_.push_back({piece, unit, back, front});
          portals_.push_back({piece, flipped(unit), front, back});
          out_[static_cast<size_t>(back)].push_back(id);
          out_[static_cast<size_t>(front)].push_back(id + 1);
        });
      });
    path.push_back(p);
    walk(n.children[0]);
    path.back() = flipped(p);
    walk(n.children[1]);
    path.pop_back();
  };
  if (!b.nodes.empty()) walk(0);
  // The outer box's faces: the empty leaves they reach are open to the outside.
  std::vector<uint8_t> open(b.leaf_count(), 0);
  const Polytope box = Polytope::box(b.bounds);
  for (const Winding& f : box.faces) {
    if (b.nodes.empty()) {
      open[0] = !b.leaf_solid[0];
      continue;
    }
    descend(b, 0, f, eps_, [&](int32_t leaf, const Winding&) {
      if (!b.leaf_solid[static_cast<size_t>(leaf)]) open[static_cast<size_t>(leaf)] = 1;
    });
  }
  for (size_t l = 0; l < open.size(); ++l)
    if (open[l]) open_.push_back(static_cast<int32_t>(l));
}

void PortalGraph::make_might_see() {
  const size_t n = portals_.size();
  words_ = (n + 63) / 64;
  might_.assign(n * words_, 0);
  // Portal q can follow p on a line only if part of q lies in front of p and part of p behind q.
  auto follows = [this](const Portal& p, const Portal& q) {
    bool front = false, behind = false;
    for (const Vec3& x : q.winding)
      if (p.plane.distance(x) > eps_) {
        front = true;
        break;
      }
    if (!front) return false;
    for (const Vec3& x : p.winding)
      if (q.plane.distance(x) < -eps_) {
        behind = true;
        break;
      }
    return behind;
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<int32_t> stack;
    for (size_t pi = r.begin(); pi < r.end(); ++pi) {
      if ((pi & 255) == 0) throw_if_interrupted("portal flood");
      uint64_t* row = &might_[pi * words_];
      const Portal& p = portals_[pi];
      stack.assign(1, p.to);
      while (!stack.empty()) {
        const int32_t leaf = stack.back();
        stack.pop_back();
        for (const uint32_t qi : out_[static_cast<size_t>(leaf)]) {
          if (test_bit(row, qi) || !follows(p, portals_[qi])) continue;
          set_bit(row, qi);
          stack.push_back(portals_[qi].to);
        }
      }
    }
  });
}

void PortalGraph::split_polygon(const Winding& w, std::vector<std::pair<int32_t, Winding>>& out) const {
  auto keep = [&](int32_t leaf, const Winding& part) {
    if (!bsp_.leaf_solid[static_cast<size_t>(leaf)]) out.emplace_back(leaf, part);
  };
  if (bsp_.nodes.empty()) keep(0, w);
  else descend(bsp_, 0, w, std::max(eps_, bsp_.surface_slack), keep);
}

void PortalGraph::split_to_leaves(const Polytope& p, std::vector<std::pair<int32_t, Polytope>>& out) const {
  std::function<void(int32_t, const Polytope&)> go = [&](int32_t child, const Polytope& part) {
    if (child < 0) {
      const int32_t leaf = -(child + 1);
      if (!bsp_.leaf_solid[static_cast<size_t>(leaf)]) out.emplace_back(leaf, part);
      return;
    }
    const SolidBsp::Node& n = bsp_.nodes[static_cast<size_t>(child)];
    const HalfPlane& h = bsp_.planes[static_cast<size_t>(n.plane)];
    // A side where the part reaches no further than the tolerance gets nothing: a sliver of no
    // volume would be a flat source, whose lines the separating planes cannot bound (its
    // points lie on the other part's boundary, and their lines are that part's).
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Winding& f : part.faces)
      for (const Vec3& v : f) {
        const double d = h.distance(v);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
    const bool flat = hi - lo <= 2 * eps_;
    if (hi > eps_ || flat) {
      Polytope front = clip_polytope(part, h, eps_);
      if (!front.empty()) go(n.children[0], front);
    }
    if (lo < -eps_ || flat) {
      Polytope back = clip_polytope(part, flipped(h), eps_);
      if (!back.empty()) go(n.children[1], back);
    }
  };
  if (bsp_.nodes.empty()) {
    if (!bsp_.leaf_solid[0]) out.emplace_back(0, p);
    return;
  }
  go(0, p);
}

void PortalGraph::place(std::vector<Placed> placed, uint32_t object_count) {
  placed_.assign(bsp_.leaf_count(), {});
  object_leaves_.assign(object_count, {});
  leaf_objects_.assign(bsp_.leaf_count(), 0);
  std::sort(placed.begin(), placed.end(),
            [](const Placed& a, const Placed& b) { return std::tie(a.leaf, a.object) < std::tie(b.leaf, b.object); });
  for (Placed& p : placed) {
    VC_CHECK(p.leaf >= 0 && static_cast<size_t>(p.leaf) < bsp_.leaf_count() && p.object < object_count);
    auto& here = placed_[static_cast<size_t>(p.leaf)];
    if (here.empty() || here.back().object != p.object) {
      object_leaves_[p.object].push_back(p.leaf);
      ++leaf_objects_[static_cast<size_t>(p.leaf)];
    }
    here.push_back(std::move(p));
  }
}

void PortalGraph::reset(FloodState& st) const {
  st.visible.assign(words_, 0);
  st.done.assign(words_, 0);
  st.overflow.assign(words_, 0);
  st.object_seen.assign(object_leaves_.size(), 0);
  st.remaining = leaf_objects_;
  if (st.remaining.size() != bsp_.leaf_count()) st.remaining.assign(bsp_.leaf_count(), 0);
}

void PortalGraph::flood(const Polytope& source, int32_t start, FloodState& st, uint64_t max_steps,
                        FloodStats& stats) const {
  VC_CHECK(st.visible.size() == words_ && st.remaining.size() == bsp_.leaf_count());
  std::vector<uint8_t> in_chain(bsp_.leaf_count(), 0);
  FloodRun run{*this, convex_of(source, eps_), st, max_steps, stats, in_chain, {}, {}, false, eps_, 10 * eps_};
  run.might.emplace_back(words_);
  run.might.emplace_back(words_);
  // What lies in the region's own leaf may be seen from it.
  for (const Placed& p : placed_[static_cast<size_t>(start)]) run.see(p.object);
  in_chain[static_cast<size_t>(start)] = 1;
  for (const uint32_t pi : out_[static_cast<size_t>(start)]) {
    if (run.overflow) {
      run.keep_all(&might_[pi * words_]);
      set_bit(st.visible.data(), pi);
      set_bit(st.overflow.data(), pi);
      continue;
    }
    const Portal& p = portals_[pi];
    const uint64_t* p_might = &might_[pi * words_];
    bool more = false;
    for (size_t w = 0; w < words_; ++w) more = more || (p_might[w] & ~st.done[w]) != 0;
    if (!more && test_bit(st.done.data(), pi)) continue;
    run.cross(pi);
    std::copy(p_might, p_might + words_, run.might[0].begin());
    in_chain[static_cast<size_t>(p.to)] = 1;
    run.recurse(p.winding, p.plane, p.to, 0);
    in_chain[static_cast<size_t>(p.to)] = 0;
  }
}

void PortalGraph::finish(FloodState& st) const {
  for (size_t w = 0; w < words_; ++w)
    for (uint64_t bits = st.overflow[w]; bits; bits &= bits - 1)
      for (const Placed& p : placed_[static_cast<size_t>(portals_[w * 64 + static_cast<size_t>(__builtin_ctzll(bits))].to)])
        st.object_seen[p.object] = 1;
}

}  // namespace viewcells
