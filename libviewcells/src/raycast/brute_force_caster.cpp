// The oracle: every triangle against every ray, in double precision, with the watertight
// ray/triangle test of Woop, Benthin and Wald (JCGT 2013) so that rays through shared edges
// and vertices always hit one of the triangles meeting there.
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <vector>

#include "viewcells/raycast/ray_caster.h"

namespace viewcells {

void RayCaster::intersect_pairs(std::span<const Vec3> origins, std::span<const Vec3> dirs, std::span<Hit> hits) const {
  std::vector<Ray> rays(2 * origins.size());
  for (size_t i = 0; i < origins.size(); ++i) {
    rays[2 * i] = Ray{origins[i], dirs[i]};
    rays[2 * i + 1] = Ray{origins[i], -dirs[i]};
  }
  intersect(rays, hits);
}

namespace {

class BruteForceCaster final : public RayCaster {
 public:
  explicit BruteForceCaster(const Scene& scene) : scene_(scene) {}

  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override {
    for (size_t i = 0; i < rays.size(); ++i) hits[i] = cast(rays[i]);
  }

  double time_raw(std::span<const Ray> rays) const override {
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(size_t{0}, rays.size(), [&](size_t i) { (void)cast(rays[i]); });
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  std::string name() const override { return "brute-force"; }

 private:
  Hit cast(const Ray& ray) const {
    // Shear/permutation set-up of the watertight test.
    const Vec3& d = ray.dir;
    int kz = 0;
    if (std::abs(d.y) > std::abs(d[kz])) kz = 1;
    if (std::abs(d.z) > std::abs(d[kz])) kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0) std::swap(kx, ky);
    const double sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.0 / d[kz];

    Hit best;
    best.t = ray.tfar;
    bool found = false;
    for (uint32_t t = 0; t < scene_.triangles.size(); ++t) {
      if (!scene_.objects[scene_.triangle_object[t]].occluder) continue;  // seen through
      const auto& tri = scene_.triangles[t];
      const Vec3 a = scene_.vertices[tri[0]] - ray.origin;
      const Vec3 b = scene_.vertices[tri[1]] - ray.origin;
      const Vec3 c = scene_.vertices[tri[2]] - ray.origin;
      const double ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
      const double bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
      const double cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];
      const double u = cx * by - cy * bx;
      const double v = ax * cy - ay * cx;
      const double w = bx * ay - by * ax;
      if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) continue;
      const double det = u + v + w;
      if (det == 0.0) continue;  // ray in the triangle's plane
      const double az = sz * a[kz], bz = sz * b[kz], cz = sz * c[kz];
      const double tt = (u * az + v * bz + w * cz) / det;
      if (!(tt >= ray.tnear && tt <= best.t)) continue;
      if (found && tt == best.t && t > best.triangle) continue;  // ties: lowest triangle id
      best.t = tt;
      best.triangle = t;
      found = true;
    }
    if (!found) return Hit{};
    best.object = scene_.triangle_object[best.triangle];
    best.front = is_front_face(scene_, best.triangle, ray.dir);
    return best;
  }

  const Scene& scene_;
};

}  // namespace

std::unique_ptr<RayCaster> make_brute_force_caster(const Scene& scene) {
  return std::make_unique<BruteForceCaster>(scene);
}

}  // namespace viewcells
