// Geometry-aligned candidate planes (paper section 4.2.2): the planes of triangles the cell's
// segments hit, bounded from each object's extreme part ends before any is evaluated on all parts.
#include "bsp/subdivision_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"

namespace viewcells::subdivision_detail {

std::optional<Vec3> Builder::plane_direction(uint32_t t) const {
  const Vec3 n = scene_.triangle_normal(t);
  const double len = length(n);
  if (!(len > 0)) return std::nullopt;
  const Vec3 u = n / len;
  if (std::max({std::abs(u.x), std::abs(u.y), std::abs(u.z)}) > 1.0 - 1e-9) return std::nullopt;
  return u;
}

bool Builder::hits_plane_source(const SegRef& s, const SegEnds& e) const {
  return (s.q0 == 0 && e.triangle_a != kNoObject && plane_source_[e.triangle_a]) ||
         (s.q1 == SegRef::kOne && e.triangle_b != kNoObject && plane_source_[e.triangle_b]);
}

Builder::GeometryParts Builder::gather_geometry_parts(int32_t node) {
  const RawVector<SegRef>& refs = refs_[node];
  // Triangles hit at segment ends inside this node lie (at least partly) inside it.
  // (Distinct ones first, by marks; then sorted: far fewer than the parts.) The same pass
  // takes, in a cell of at most kBoundedParts parts, the parts' end points and objects, in
  // order, for all the planes' passes; in a larger one, each object's extreme part ends, from
  // which the planes are bounded (best_geometry_candidate). A large cell's parts are not kept:
  // only about one of its planes in 25 is then evaluated on all of them (oa_shouse: 1,251 of
  // 31,732), and that pass reads them again from the segments (BENCHMARKS.md, "Decisions
  // measured").
  constexpr size_t kBoundedParts = 2048;
  GeometryParts g;
  g.large = refs.size() > kBoundedParts;
  if (!g.large) g.parts.resize(refs.size());
  Marks& seen = triangle_marks_.local();
  seen.reset(scene_.triangles.size());
  // Object -> its entry in extremes; this thread's, left all UINT32_MAX again after use.
  std::vector<uint32_t>& entry = extreme_entry_.local();
  if (g.large && entry.size() < r_.size()) entry.assign(r_.size(), UINT32_MAX);
  // A part's ends lowest and highest along each axis (p0 on a tie), which update its objects'
  // extremes as p0 and then p1 would.
  Vec3 part_ends[ObjectExtremes::kEnds];
  auto extend = [&](uint32_t o) {
    if (o == kNoObject) return;
    uint32_t& at = entry[o];
    if (at != UINT32_MAX) {
      g.extremes[at].add(part_ends);
      return;
    }
    at = static_cast<uint32_t>(g.extremes.size());
    g.extremes.emplace_back(o, part_ends);
  };
  for (size_t i = 0; i < refs.size(); ++i) {
    prefetch_ends(refs, i);
    const SegRef& s = refs[i];
    const SegEnds& e = ends_[s.id];
    if (s.q0 == 0 && seen.first(e.triangle_a)) g.tris.push_back(e.triangle_a);
    if (s.q1 == SegRef::kOne && seen.first(e.triangle_b)) g.tris.push_back(e.triangle_b);
    const Vec3 p0 = e.at(s.t0()), p1 = e.at(s.t1());
    g.points.extend(p0);
    g.points.extend(p1);
    if (g.large) {
      for (int axis = 0; axis < 3; ++axis) {
        part_ends[2 * axis] = p1[axis] < p0[axis] ? p1 : p0;
        part_ends[2 * axis + 1] = p1[axis] > p0[axis] ? p1 : p0;
      }
      extend(e.object_a);
      if (e.object_b != e.object_a) extend(e.object_b);
    } else {
      g.parts[i] = {p0, p1, e.object_a, e.object_b};
    }
  }
  for (const ObjectExtremes& x : g.extremes) entry[x.object] = UINT32_MAX;
  std::sort(g.tris.begin(), g.tris.end());
  return g;
}

std::vector<uint32_t> Builder::geometry_planes(int32_t node, const std::vector<uint32_t>& tris) const {
  // One candidate per distinct plane (walls are made of several triangles).
  std::map<std::array<long long, 4>, uint32_t> by_plane;
  for (uint32_t t : tris) {
    const std::optional<Vec3> direction = plane_direction(t);
    if (!direction) continue;
    const Vec3& u = *direction;
    const double d = dot(u, scene_.vertices[scene_.triangles[t][0]]);
    const double q = 1e6 / std::max(1.0, out_.view_box.diagonal());
    by_plane.emplace(std::array<long long, 4>{std::llround(u.x * 1e6), std::llround(u.y * 1e6),
                                              std::llround(u.z * 1e6), std::llround(d * q)},
                     t);
  }
  std::vector<uint32_t> planes;
  for (const auto& [key, t] : by_plane) planes.push_back(t);
  if (planes.size() > config_.ga_candidates) {
    Rng rng(config_.seed, (static_cast<uint64_t>(node) << 2) | 3);
    for (size_t i = 0; i < config_.ga_candidates; ++i)
      std::swap(planes[i], planes[i + rng.below(planes.size() - i)]);
    planes.resize(config_.ga_candidates);
  }
  return planes;
}

std::pair<double, double> Builder::geometry_side_costs(int32_t node, const GeometryParts& g, const Plane& plane,
                                                       bool from_extremes, const double* r) {
  // What each side of a plane sees, r(PVS) summed: exact from all the parts (each plane costs
  // O(n)), or from below by the extremes: an object one of whose extreme part ends lies strictly
  // on a side is seen from there (that end's part touches the side), so those objects are a
  // subset of what each side sees, each side's r(PVS) can only grow from theirs, and the
  // reduction can only fall.
  const FilteredSide side(plane, g.points);
  // Plain references, not a structured binding: clang 14 (the fuzz and sanitizer builds)
  // refuses bindings captured by the lambdas below.
  std::pair<Marks, Marks>& sides = side_pair_marks_.local();
  Marks& neg = sides.first;
  Marks& pos = sides.second;
  neg.reset(r_.size());
  pos.reset(r_.size());
  double cl = 0, cr = 0;
  if (from_extremes) {
    for (const ObjectExtremes& x : g.extremes) {
      bool on_neg = false, on_pos = false;
      for (int k = 0; k < ObjectExtremes::kEnds && !(on_neg && on_pos); ++k) {
        const int at = side(x.end[k]);
        on_neg |= at < 0;
        on_pos |= at > 0;
      }
      if (on_neg) cl += neg.add(x.object, r);
      if (on_pos) cr += pos.add(x.object, r);
    }
    return {cl, cr};
  }
  // A part whose objects both sides have seen adds nothing: its sides are not needed.
  auto add = [&](const Vec3& p0, const Vec3& p1, uint32_t a, uint32_t b) {
    const int to = classify(side(p0), side(p1));
    if (to & 1) cl += neg.add(a, r) + neg.add(b, r);
    if (to & 2) cr += pos.add(a, r) + pos.add(b, r);
  };
  auto known = [&](uint32_t a, uint32_t b) { return neg.seen(a) && neg.seen(b) && pos.seen(a) && pos.seen(b); };
  if (g.large) {
    const RawVector<SegRef>& refs = refs_[node];
    for (size_t i = 0; i < refs.size(); ++i) {
      prefetch_ends(refs, i);
      const SegRef& s = refs[i];
      const SegEnds& e = ends_[s.id];
      if (known(e.object_a, e.object_b)) continue;
      add(e.at(s.t0()), e.at(s.t1()), e.object_a, e.object_b);
    }
  } else {
    for (const GeometryParts::PartEnds& e : g.parts)
      if (!known(e.object_a, e.object_b)) add(e.p0, e.p1, e.object_a, e.object_b);
  }
  return {cl, cr};
}

Candidate Builder::best_geometry_candidate(int32_t node, Evaluation& ev, const double* r, double to_beat) {
  // About half the cells of oa_shouse hold no end on a plane source: no pass over their parts.
  if (!plane_hits_[node]) return {};
  const GeometryParts g = gather_geometry_parts(node);
  const std::vector<uint32_t> planes = geometry_planes(node, g.tris);
  if (planes.empty()) return {};
  const double own = node_cost(node);
  const double volume = out_.nodes[node].volume, weight = out_.nodes[node].weight;
  const ConvexPolyhedron& cell = out_.cells[node];
  const ConvexPolyhedron part = config_.density.enabled ? config_.density.band_part(cell) : ConvexPolyhedron();
  // The weight below a plane: the viewpoints on its negative side (each by the exact side, its
  // filter bounded by their box), or its volume below (or in the density's band).
  Box3 viewpoint_box;
  if (points_)
    for (uint32_t i : pts_[node]) viewpoint_box.extend((*config_.viewpoints)[i]);
  auto weight_below = [&](const Plane& plane, double vl) {
    if (points_) {
      const FilteredSide side(plane, viewpoint_box);
      uint64_t below = 0;
      for (uint32_t i : pts_[node]) below += side((*config_.viewpoints)[i]) <= 0;
      return static_cast<double>(below) * point_weight_;
    }
    if (config_.density.enabled) return config_.density.weight_below(cell, part, plane);
    return vl;
  };
  auto reduction = [&](double wl, std::pair<double, double> costs) {
    return own - (wl * costs.first + (weight - wl) * costs.second) / total_weight_;
  };
  // In a cell of more than kBoundedParts parts, every plane is first bounded from its
  // objects' extreme ends (O(objects), where most objects are seen across much of the cell),
  // then evaluated on all parts in the order of the bounds until the next bound is below the
  // best exact reduction (with a margin for rounding): the same choice as evaluating them all.
  // On oa_shouse about one plane in 25 is then evaluated on all parts. (Bounds from 512
  // evenly spaced parts, used before, missed so many objects on each side that nearly every
  // plane was evaluated on all parts.)
  const bool bounded = g.large && planes.size() > 1;
  // The planes in parallel, the best chosen in their order: ties keep the first.
  const double margin = 1e-9 * std::abs(own) + 1e-300;  // for rounding
  std::vector<Candidate> results(planes.size());
  std::vector<double> below(planes.size());  // each plane's weight below, for its exact pass
  tbb::parallel_for(size_t{0}, planes.size(), [&](size_t j) {
    const auto& tri = scene_.triangles[planes[j]];
    const Plane plane = Plane::through(scene_.vertices[tri[0]], scene_.vertices[tri[1]], scene_.vertices[tri[2]]);
    const double vl = cell.volume_below(plane), vr = volume - vl;
    if (!(vl > kMinPart * volume && vr > kMinPart * volume)) return;
    const auto costs = geometry_side_costs(node, g, plane, bounded, r);
    if (bounded) {
      // Whatever the weight below (0 to the cell's), the reduction is at most this. A plane
      // it leaves below the axis split (by more than rounding) cannot be chosen, and its
      // weight below, a pass over the cell's viewpoints with a viewpoint density, is not needed.
      const double any_weight = own - weight * std::min(costs.first, costs.second) / total_weight_;
      if (any_weight < to_beat - 2 * margin) return;
    }
    below[j] = weight_below(plane, vl);
    results[j] = {true, plane, reduction(below[j], costs)};
  });
  if (bounded)
    evaluate_best_bounds(results, to_beat, margin, [&](size_t j) {
      return reduction(below[j], geometry_side_costs(node, g, results[j].plane, false, r));
    });
  // The planes still valid are those evaluated on all parts.
  __atomic_add_fetch(&ev.geometry_full,
                     static_cast<uint64_t>(std::count_if(results.begin(), results.end(),
                                                         [](const Candidate& c) { return c.valid; })),
                     __ATOMIC_RELAXED);
  Candidate best;
  for (const Candidate& c : results)
    if (c.valid && (!best.valid || c.reduction > best.reduction)) best = c;
  __atomic_add_fetch(&ev.geometry, planes.size(), __ATOMIC_RELAXED);
  return best;
}

void Builder::evaluate_best_bounds(std::vector<Candidate>& results, double to_beat, double margin,
                                   const std::function<double(size_t)>& exact) {
  // The planes by their bounds, highest first, each replaced by its exact reduction in batches
  // of four (in parallel) until the next bound is below the best exact one: no later plane can
  // win. The planes never evaluated exactly are left out.
  std::vector<size_t> order;
  for (size_t j = 0; j < results.size(); ++j)
    if (results[j].valid) order.push_back(j);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return results[a].reduction > results[b].reduction || (results[a].reduction == results[b].reduction && a < b);
  });
  std::vector<char> evaluated(results.size(), 0);
  double best_exact = to_beat;
  for (size_t next = 0; next < order.size();) {
    if (results[order[next]].reduction < best_exact - margin) break;  // no later plane can win
    const size_t batch = std::min(order.size(), next + 4);
    tbb::parallel_for(next, batch, [&](size_t i) { results[order[i]].reduction = exact(order[i]); });
    for (; next < batch; ++next) {
      evaluated[order[next]] = 1;
      best_exact = std::max(best_exact, results[order[next]].reduction);
    }
  }
  for (size_t j = 0; j < results.size(); ++j)
    if (!evaluated[j]) results[j].valid = false;  // bounded below the best: cannot be chosen
}

}  // namespace viewcells::subdivision_detail
