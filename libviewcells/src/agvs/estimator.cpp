// AGVS paper 4.5: termination by the pixel error: the estimate from the view space-direction
// rays (equation 5), its bound, and the measurement by rendered cameras that checks it.
#include "solver_impl.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <numeric>
#include <span>

namespace viewcells {

void AgvsSolver::Impl::update_estimate(uint64_t rays, uint64_t wrong) {
  window.emplace_front(rays, wrong);
  window_total += rays;
  evaluate_window();
}

void AgvsSolver::Impl::evaluate_window() {
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

}  // namespace viewcells
