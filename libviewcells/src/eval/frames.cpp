// Frames rendered at cameras: the measured pixel error of a PVS (AGVS paper 4.5) and what a
// viewer's frames show, for any PVS of a scene.
#include "viewcells/eval/frames.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <iterator>
#include <numeric>

#include "agvs/halton.h"
#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/interrupt.h"

namespace viewcells {

using agvs_detail::sphere_direction;

Camera camera_looking_anywhere(const Vec3& eye, Rng& rng) {
  Camera cam;
  cam.eye = eye;
  cam.forward = sphere_direction(rng.uniform(), rng.uniform());
  Vec3 right, up;
  orthonormal_basis(cam.forward, right, up);
  const double roll = 2 * std::numbers::pi * rng.uniform();  // random orientation about the view axis
  cam.right = right * std::cos(roll) + up * std::sin(roll);
  cam.up = cross(cam.right, cam.forward) * -1.0;
  return cam;
}

Camera camera_looking(const Vec3& eye, double yaw, double pitch) {
  Camera cam;
  cam.eye = eye;
  cam.forward = {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
  cam.right = {std::sin(yaw), -std::cos(yaw), 0};
  cam.up = cross(cam.right, cam.forward);
  return cam;
}

std::vector<Camera> view_box_cameras(const RayCaster& caster, const CellLocator& locator, uint32_t count,
                                     uint64_t seed, bool skip_inside_solids, std::vector<int32_t>& cells) {
  Rng rng(seed, 77);
  const Box3& box = locator.view_box();
  std::vector<Camera> cams;
  cams.reserve(count);
  cells.assign(count, -1);
  for (uint32_t k = 0; k < count; ++k) {
    Vec3 eye;
    for (int tries = 0;; ++tries) {
      if (tries > 100000) throw Error("no camera position found outside the solids");
      eye = {rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y), rng.uniform(box.lo.z, box.hi.z)};
      cells[k] = locator.cell_at(eye);
      if (cells[k] < 0) continue;
      if (!skip_inside_solids) break;
      const Hit probe = caster.intersect(Ray{eye, sphere_direction(rng.uniform(), rng.uniform())});
      if (!probe.hit() || probe.front) break;  // a back face first: the eye is inside a solid
    }
    cams.push_back(camera_looking_anywhere(eye, rng));
  }
  return cams;
}

void check_frame_budget(uint64_t cameras, uint32_t width, uint32_t height) {
  if (cameras == 0 || width == 0 || height == 0) throw Error("the pixel error needs cameras and pixels");
  const uint64_t pixels = uint64_t{width} * height;
  if (cameras > kMaxFrameRays / pixels)
    throw Error(std::to_string(cameras) + " cameras of " + std::to_string(width) + "x" + std::to_string(height) +
                " pixels cast " + fmt(static_cast<double>(cameras) * static_cast<double>(pixels), 0) +
                " primary rays, above the ceiling of " +
                std::to_string(kMaxFrameRays) + " (2^32) a measurement may cast: fewer cameras or pixels");
}

void frame_rays(const Camera& cam, const FrameConfig& config, std::vector<Ray>& rays) {
  const uint32_t width = config.width, height = config.height;
  const double f = std::tan(0.5 * config.fov_degrees * std::numbers::pi / 180.0);
  const double aspect = static_cast<double>(height) / width;
  rays.resize(size_t(width) * height);
  constexpr uint32_t kTile = 4;
  size_t at = 0;
  for (uint32_t ty = 0; ty < height; ty += kTile)
    for (uint32_t tx = 0; tx < width; tx += kTile)
      for (uint32_t y = ty; y < std::min(ty + kTile, height); ++y)
        for (uint32_t x = tx; x < std::min(tx + kTile, width); ++x) {
          const double sx = (2 * (x + 0.5) / width - 1) * f, sy = (2 * (y + 0.5) / height - 1) * f * aspect;
          rays[at++] = Ray{cam.eye, normalize(cam.forward + cam.right * sx + cam.up * sy)};
        }
}

namespace {

/// The frame's hits, in slices of 4096 rays over all threads (a large frame uses every core).
void cast_frame(const RayCaster& caster, const std::vector<Ray>& rays, std::vector<Hit>& hits, bool coherent) {
  hits.resize(rays.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    const std::span<const Ray> in(rays.data() + r.begin(), r.size());
    const std::span<Hit> out(hits.data() + r.begin(), r.size());
    if (coherent) caster.intersect_coherent(in, out);
    else caster.intersect(in, out);
  });
}

}  // namespace

FrameRayRates frame_ray_rates(const RayCaster& caster, std::span<const Camera> cameras, const FrameConfig& config,
                              uint64_t max_rays) {
  // Frame by frame (one frame's rays in memory: 50 MB at 1024x768), each cast both ways twice,
  // alternating; the second round is timed.
  FrameRayRates out;
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  double seconds[2] = {0, 0};
  for (const Camera& cam : cameras) {
    if (out.rays >= max_rays) break;
    frame_rays(cam, config, rays);
    out.rays += rays.size();
    for (int round = 0; round < 2; ++round)
      for (int coherent = 1; coherent >= 0; --coherent) {
        Stopwatch sw;
        cast_frame(caster, rays, hits, coherent);
        if (round == 1) seconds[coherent] += sw.seconds();
      }
  }
  out.coherent_per_second = out.rays / std::max(seconds[1], 1e-9);
  out.incoherent_per_second = out.rays / std::max(seconds[0], 1e-9);
  return out;
}

uint64_t add_frame_samples(const RayCaster& caster, std::span<const Camera> cameras, std::span<const int32_t> cells,
                           const FrameConfig& config, std::vector<std::vector<uint32_t>>& lists) {
  check_frame_budget(cameras.size(), config.width, config.height);
  if (cells.size() != cameras.size()) throw Error("add_frame_samples: one cell per camera");
  const size_t n = cameras.size();
  std::vector<std::vector<uint32_t>> seen(n);  // per camera: the objects it shows, sorted
  Progress progress("frame samples", n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    for (size_t k = range.begin(); k < range.end(); ++k) {
      throw_if_interrupted("frame samples");
      if (cells[k] < 0 || config.deadline.passed()) continue;  // past the deadline: adds nothing
      frame_rays(cameras[k], config, rays);
      cast_frame(caster, rays, hits, true);
      for (const Hit& h : hits)
        if (h.hit()) seen[k].push_back(h.object);
      std::sort(seen[k].begin(), seen[k].end());
      seen[k].erase(std::unique(seen[k].begin(), seen[k].end()), seen[k].end());
      progress.advance();
    }
  });
  progress.finish();
  // Serially, camera by camera: the lists do not depend on the threads.
  uint64_t added = 0;
  std::vector<uint32_t> merged;
  for (size_t k = 0; k < n; ++k) {
    if (cells[k] < 0 || seen[k].empty()) continue;
    std::vector<uint32_t>& list = lists.at(static_cast<size_t>(cells[k]));
    merged.clear();
    std::set_union(list.begin(), list.end(), seen[k].begin(), seen[k].end(), std::back_inserter(merged));
    added += merged.size() - list.size();
    list.swap(merged);
  }
  return added;
}

PixelErrorMeasure measure_frames(const Scene& scene, const RayCaster& caster, std::span<const Camera> cameras,
                                 std::span<const int32_t> cells, const GlobalPvs& pvs, const FrameConfig& config) {
  const uint32_t width = config.width, height = config.height;
  check_frame_budget(cameras.size(), width, height);
  if (!(config.fov_degrees > 0 && config.fov_degrees < 180))
    throw Error("the field of view must be between 0 and 180 degrees");
  if (cells.size() != cameras.size()) throw Error("measure_frames: one cell per camera");
  for (int32_t c : cells)
    if (c < -1 || (c >= 0 && static_cast<uint32_t>(c) >= pvs.cell_count()))
      throw Error("measure_frames: a camera's cell is not one of the PVS's");
  const uint32_t asked = static_cast<uint32_t>(cameras.size());
  std::vector<std::vector<WrongView>> wrong_of(asked);
  std::vector<uint8_t> done(asked, 0);
  Progress progress("frames", asked);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, asked, 1), [&](const tbb::blocked_range<uint32_t>& range) {
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    std::vector<uint32_t> objects, count(scene.objects.size(), 0);
    for (uint32_t k = range.begin(); k < range.end(); ++k) {
      throw_if_interrupted("measuring frames");
      if (config.deadline.passed()) continue;  // past the deadline: left out, not counted
      frame_rays(cameras[k], config, rays);
      cast_frame(caster, rays, hits, config.coherent);
      // Counted per object (a frame of 786K pixels is not sorted): the objects met, then
      // their counts in id order.
      objects.clear();
      for (const Hit& h : hits)
        if (h.hit() && scene.objects[h.object].rendered &&
            (cells[k] < 0 || !pvs.contains(static_cast<uint32_t>(cells[k]), h.object)) && count[h.object]++ == 0)
          objects.push_back(h.object);
      std::sort(objects.begin(), objects.end());
      for (uint32_t o : objects) {
        wrong_of[k].push_back({k, o, count[o]});
        count[o] = 0;
      }
      done[k] = 1;
      progress.advance();
    }
  });
  progress.finish();
  PixelErrorMeasure out;
  out.cameras_asked = asked;
  // Cut by the deadline, the measure is over the first cameras all done (cameras are drawn
  // independently, so these are a smaller sample of the same distribution).
  const uint32_t n = static_cast<uint32_t>(std::find(done.begin(), done.end(), 0) - done.begin());
  out.cameras = n;
  if (n == 0) return out;
  std::vector<uint64_t> per_camera(n, 0);
  for (uint32_t k = 0; k < n; ++k) {
    for (const WrongView& w : wrong_of[k]) per_camera[k] += w.pixels;
    out.cameras_wrong += per_camera[k] > 0;
    out.cameras_uncovered += cells[k] < 0;
    out.wrong.insert(out.wrong.end(), wrong_of[k].begin(), wrong_of[k].end());
  }
  const uint64_t wrong = std::accumulate(per_camera.begin(), per_camera.end(), uint64_t{0});
  const double frame = static_cast<double>(width) * height;
  out.share = static_cast<double>(wrong) / (frame * n);
  out.pixels = out.share * config.resolution;
  std::nth_element(per_camera.begin(), per_camera.begin() + n / 2, per_camera.end());
  double median = static_cast<double>(per_camera[n / 2]);
  if (n % 2 == 0) median = 0.5 * (median + static_cast<double>(*std::max_element(per_camera.begin(), per_camera.begin() + n / 2)));
  out.median_pixels = median / frame * config.resolution;
  // Nearest rank: the smallest count that at least 99% of the cameras do not exceed.
  const size_t rank = (99 * static_cast<size_t>(n) + 99) / 100 - 1;
  std::nth_element(per_camera.begin(), per_camera.begin() + rank, per_camera.end());
  out.p99_pixels = static_cast<double>(per_camera[rank]) / frame * config.resolution;
  out.worst_pixels =
      static_cast<double>(*std::max_element(per_camera.begin(), per_camera.end())) / frame * config.resolution;
  return out;
}

PixelErrorMeasure measure_pixel_error(const Scene& scene, const RayCaster& caster, const CellLocator& cells,
                                      const GlobalPvs& pvs, uint32_t cameras, uint32_t width, uint32_t height,
                                      double fov_degrees, uint64_t seed, bool skip_inside_solids,
                                      uint32_t resolution) {
  if (cameras == 0 || width == 0 || height == 0) throw Error("the pixel error needs cameras and pixels");
  std::vector<int32_t> cam_cells;
  const std::vector<Camera> cams = view_box_cameras(caster, cells, cameras, seed, skip_inside_solids, cam_cells);
  return measure_frames(scene, caster, cams, cam_cells, pvs, FrameConfig{width, height, fov_degrees, resolution});
}

}  // namespace viewcells
