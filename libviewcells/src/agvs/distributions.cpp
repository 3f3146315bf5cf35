// AGVS paper 4.3 and 4.4: drawing a sample from each distribution of the mixture: view space-direction,
// object-direction and two-point (stationary), two-point and silhouette mutations.
#include "solver_impl.h"

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

double AgvsSolver::Impl::sample_share(int d) {
  if (d == kOd || (!config.view_space && !config.view_point_map)) return 1.0;
  constexpr uint64_t kPilot = 4096;
  if (halton_index[d] >= kPilot)
    return (static_cast<double>(stats.dist_samples[d]) + 1) / (static_cast<double>(halton_index[d]) + 2);
  if (pilot_share[d] < 0) {
    std::vector<Vec3> points, dirs;
    draw_stationary(d, 0, kPilot, points, dirs);
    pilot_share[d] = (static_cast<double>(points.size()) + 1) / (kPilot + 2);
  }
  return pilot_share[d];
}

void AgvsSolver::Impl::draw_stationary(int d, uint64_t first, uint32_t count, std::vector<Vec3>& points,
                                       std::vector<Vec3>& dirs) const {
  // Most of a map's view box may be solid: its view points outside the view space are skipped.
  const Halton& h = halton[d];
  const int dim = d == kTp ? 4 : 0;
  const bool space = config.view_space || config.view_point_map;
  for (uint64_t i = first; i < first + count; ++i) {
    Vec3 at{};
    if (d != kOd) {
      at = view_point(h.at(i, dim), h.at(i, dim + 1), h.at(i, dim + 2));
      if (space && (std::isnan(at.x) || (config.view_space && !config.view_space(at)))) continue;
    }
    Vec3 point, dir;
    if (!stationary_sample(d, i, at, point, dir)) continue;
    points.push_back(point);
    dirs.push_back(dir);
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
