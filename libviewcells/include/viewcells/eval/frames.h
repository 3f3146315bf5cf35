#pragma once
/// What a viewer gets from a shipped PVS, measured by frames: cameras stand in the view
/// space, and each is rendered by ray casting against the whole scene. A pixel is wrong when
/// the object it shows is not in the PVS of the camera's view cell (an engine drawing only
/// that PVS would show something else there). The same cameras measure any PVS of the scene
/// (ours, a map compiler's), so two can be compared frame by frame.
#include <cstdint>
#include <span>
#include <vector>

#include "viewcells/core/interrupt.h"
#include "viewcells/cells/view_cells.h"
#include "viewcells/core/rng.h"
#include "viewcells/core/vec3.h"
#include "viewcells/pvs/global_pvs.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// A pinhole camera: `forward` is the view axis, `right` and `up` span the image plane (all
/// unit length, orthogonal).
struct Camera {
  Vec3 eye, forward, right, up;
};

/// A camera at `eye` looking anywhere: forward uniform on the sphere, a random roll about it.
Camera camera_looking_anywhere(const Vec3& eye, Rng& rng);
/// A camera at `eye` as a player holds it: `yaw` about the vertical (+z) axis, `pitch` up
/// from the horizontal (radians, |pitch| < pi/2), no roll.
Camera camera_looking(const Vec3& eye, double yaw, double pitch);

/// Cameras at uniform random points of the locator's view box that lie in a cell, looking
/// anywhere (the AGVS estimator's definition, paper section 4.5). With `skip_inside_solids`
/// (scenes of closed objects), a point whose random probe ray meets a back face first is inside
/// a solid and drawn again. Drawn serially from `seed`: reproducible. `cells` receives each
/// camera's cell.
std::vector<Camera> view_box_cameras(const RayCaster& caster, const CellLocator& locator, uint32_t count,
                                     uint64_t seed, bool skip_inside_solids, std::vector<int32_t>& cells);

/// The most primary rays one measurement casts (cameras x width x height): 2^32, about 4.3
/// billion, so that no option, however large, makes a run without a bound (at a few million
/// rays a second a core, this ceiling is already about ten minutes on two cores).
constexpr uint64_t kMaxFrameRays = uint64_t{1} << 32;

/// Throws Error when `cameras` frames of width x height exceed kMaxFrameRays (or are empty).
void check_frame_budget(uint64_t cameras, uint32_t width, uint32_t height);

struct FrameConfig {
  uint32_t width = 32, height = 32;
  double fov_degrees = 90;            ///< horizontal
  uint32_t resolution = 1024 * 1024;  ///< wrong pixels are reported per frame of this many pixels
  /// Cast each frame's rays as coherent packets of 4x4 pixels (RayCaster::intersect_coherent);
  /// false: as incoherent rays (for the A/B of their rates).
  bool coherent = true;
  /// When it passes, the frames not yet rendered are left out (measure_frames: the statistics
  /// are over the first cameras done, PixelErrorMeasure::cameras of cameras_asked).
  Deadline deadline{};
};

/// A frame's primary rays, 4x4 pixel tile after tile (rows of tiles, pixels in a tile row by
/// row; tiles clipped at the right and bottom edges): neighbours next to each other, so that
/// packets of 16 are coherent. `rays` is resized to width x height.
void frame_rays(const Camera& camera, const FrameConfig& config, std::vector<Ray>& rays);

/// Primary rays a second cast coherently and incoherently over the same frames, measured one
/// after the other in the same run (Embree's packets against its stream of single rays).
struct FrameRayRates {
  uint64_t rays = 0;
  double coherent_per_second = 0, incoherent_per_second = 0;
};
/// Casts the frames of the first cameras (about `max_rays` rays) both ways, on all threads,
/// frame by frame (each twice each way, alternating; the second round timed).
FrameRayRates frame_ray_rates(const RayCaster& caster, std::span<const Camera> cameras, const FrameConfig& config,
                              uint64_t max_rays = 4'000'000);

/// An object shown at a camera although the camera's cell's PVS lacks it.
struct WrongView {
  uint32_t camera = 0;
  uint32_t object = 0;
  uint32_t pixels = 0;  ///< pixels of the camera's frame that show it
};

struct PixelErrorMeasure {
  double pixels = 0;         ///< mean wrong pixels per camera, scaled to `resolution`
  double share = 0;          ///< wrong pixels / all pixels
  double median_pixels = 0;  ///< median over the cameras of their wrong pixels, scaled to `resolution`
  double p99_pixels = 0;     ///< 99th percentile over the cameras (nearest rank), scaled to `resolution`
  double worst_pixels = 0;   ///< the worst camera's, scaled to `resolution`
  uint32_t cameras = 0;           ///< cameras measured (all asked, unless the deadline cut them)
  uint32_t cameras_asked = 0;     ///< cameras given; the statistics are over the first `cameras`
  uint32_t cameras_wrong = 0;     ///< cameras with at least one wrong pixel
  /// Cameras in no view cell (cell -1): an engine gets no PVS there and draws nothing, so every
  /// pixel showing an object is wrong. A bake must leave none; counted among cameras_wrong
  /// when they see anything.
  uint32_t cameras_uncovered = 0;
  std::vector<WrongView> wrong;   ///< every (camera, object) with wrong pixels, by camera then object

  /// The share of frames with any wrong pixel (the holes a player sees), 0 to 1.
  double wrong_frame_share() const { return cameras ? static_cast<double>(cameras_wrong) / cameras : 0.0; }
};

/// Renders every camera (in parallel; the result does not depend on the thread count) and
/// counts the pixels whose object (rendered objects only; see-through objects do not stop the
/// camera's rays and are not counted) is missing from pvs's row `cells[k]` (each < the PVS's
/// cell count, or -1: a camera in no cell, whose every object pixel is wrong).
PixelErrorMeasure measure_frames(const Scene& scene, const RayCaster& caster, std::span<const Camera> cameras,
                                 std::span<const int32_t> cells, const GlobalPvs& pvs, const FrameConfig& config);

/// Frames as a sampler (what Unreal's precomputed visibility does): renders each camera's frame
/// (coherent packets) and adds every object it shows to the PVS `lists[cells[k]]` of the
/// camera's cell (cells -1 are skipped); lists stay sorted. Returns the entries added. The
/// cameras must not be those that measure: a sampler's own cameras would hide its holes.
uint64_t add_frame_samples(const RayCaster& caster, std::span<const Camera> cameras, std::span<const int32_t> cells,
                           const FrameConfig& config, std::vector<std::vector<uint32_t>>& lists);

/// The measured pixel error of a solution (paper section 4.5, the estimator's definition):
/// cameras at uniform random points of the view box, randomly oriented, `width` x `height`
/// pixels over a `fov_degrees` horizontal field of view, rendered by ray casting. A pixel is
/// wrong when the object it shows with the full scene is not in the PVS of the camera's
/// cell (with the PVS alone it would show something else). Cameras inside solids are drawn
/// again when `skip_inside_solids` (scenes of closed objects). Returns wrong pixels per
/// camera, scaled to `resolution` pixels.
PixelErrorMeasure measure_pixel_error(const Scene& scene, const RayCaster& caster, const CellLocator& cells,
                                      const GlobalPvs& pvs, uint32_t cameras, uint32_t width, uint32_t height,
                                      double fov_degrees, uint64_t seed, bool skip_inside_solids,
                                      uint32_t resolution = 1024 * 1024);

}  // namespace viewcells
