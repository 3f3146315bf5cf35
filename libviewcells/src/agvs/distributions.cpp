// AGVS paper 4.3 and 4.4: drawing a sample from each distribution of the mixture: view space-direction,
// object-direction and two-point (stationary), two-point and silhouette mutations.
#include "solver_impl.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace viewcells {

void AgvsSolver::Impl::bind(const Scene& s, const RayCaster& rc) {
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

Vec3 AgvsSolver::Impl::object_point(double u0, double u1, double u2, double u3, Vec3& normal) const {
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

void AgvsSolver::Impl::view_points(int d, int dim, uint32_t attempts, std::vector<uint64_t>& index,
                                   std::vector<Vec3>& point) {
  const Halton& h = halton[d];
  index.assign(attempts, kNoIndex);
  point.assign(attempts, Vec3{});
  auto at = [&](uint64_t i) { return view_point(h.at(i, dim), h.at(i, dim + 1), h.at(i, dim + 2)); };
  if (!config.view_space && !config.view_point_map) {
    const uint64_t first = halton_index[d];
    halton_index[d] += attempts;
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, attempts, 256), [&](const tbb::blocked_range<uint32_t>& r) {
      for (uint32_t k = r.begin(); k < r.end(); ++k) index[k] = first + k, point[k] = at(first + k);
    });
    return;
  }
  // Most of a map's view box may be solid: points outside the view space are skipped, and an
  // attempt that meets kMaxTries of them in a row fails (a view space of nearly no volume must
  // not stall the batch). The points are tested a block at a time in parallel (blocks sized
  // from the share inside so far: only their cost depends on it) and taken in order.
  constexpr uint32_t kMaxTries = 10000;
  uint32_t k = 0, tries = 0;
  uint64_t tested = 0, inside_count = 0;
  std::vector<Vec3> candidates;
  std::vector<uint8_t> inside;
  while (k < attempts) {
    const double share = (inside_count + 1.0) / (tested + 2.0);
    const size_t block =
        std::clamp<size_t>(static_cast<size_t>(1.1 * (attempts - k) / share) + 64, 256, size_t{1} << 20);
    const uint64_t first = halton_index[d];
    candidates.resize(block);
    inside.resize(block);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, block, 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t j = r.begin(); j < r.end(); ++j) {
        candidates[j] = at(first + j);
        inside[j] = !std::isnan(candidates[j].x) && (!config.view_space || config.view_space(candidates[j])) ? 1 : 0;
      }
    });
    size_t used = 0;
    for (; used < block && k < attempts; ++used) {
      ++tries;
      if (inside[used]) {
        index[k] = first + used, point[k] = candidates[used];
        ++k, ++inside_count, tries = 0;
      } else if (tries == kMaxTries) {
        ++k, tries = 0;  // this attempt fails
      }
    }
    halton_index[d] = first + used;
    tested += used;
  }
}

bool AgvsSolver::Impl::stationary_sample(int d, uint64_t i, const Vec3& at, Vec3& point, Vec3& dir) const {
  const Halton& h = halton[d];
  switch (d) {
    case kVsd:
      point = at;
      dir = sphere_direction(h.at(i, 3), h.at(i, 4));
      return true;
    case kOd: {
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
      point = at;
      Vec3 n;
      const Vec3 o = object_point(h.at(i, 0), h.at(i, 1), h.at(i, 2), h.at(i, 3), n);
      const Vec3 to = o - point;
      if (!(length(to) > eps)) return false;
      dir = normalize(to);
      return true;
    }
  }
  return false;
}

uint32_t AgvsSolver::Impl::stationary_samples(int d, uint32_t attempts, std::vector<Vec3>& points,
                                              std::vector<Vec3>& dirs) {
  std::vector<uint64_t> index;
  std::vector<Vec3> at;
  if (d == kOd) {  // object points: every index gives a sample
    index.resize(attempts);
    for (uint32_t k = 0; k < attempts; ++k) index[k] = halton_index[d]++;
    at.assign(attempts, Vec3{});
  } else {
    view_points(d, d == kTp ? 4 : 0, attempts, index, at);
  }
  std::vector<Vec3> p(attempts), dir(attempts);
  std::vector<uint8_t> ok(attempts);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, attempts, 256), [&](const tbb::blocked_range<uint32_t>& r) {
    for (uint32_t k = r.begin(); k < r.end(); ++k)
      ok[k] = index[k] != kNoIndex && stationary_sample(d, index[k], at[k], p[k], dir[k]);
  });
  uint32_t failed = 0;
  for (uint32_t k = 0; k < attempts; ++k) {
    if (!ok[k]) {
      ++failed;
      continue;
    }
    points.push_back(p[k]);
    dirs.push_back(dir[k]);
  }
  return failed;
}

bool AgvsSolver::Impl::draw_two_point_mutation(Rng& rng, MutationLane& lane, Vec3& point, Vec3& dir) {
  if (lane.two_point.empty()) return false;
  const Candidate& c = lane.two_point.take();
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

int AgvsSolver::Impl::silhouette_samples(const Candidate& c, const double angle_u[2], Vec3 points_out[2], Vec3 dirs_out[2],
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

}  // namespace viewcells
