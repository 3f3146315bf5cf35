#pragma once
/// Closest-hit ray casting against a Scene. Two implementations: Embree 3 (fast, the default)
/// and brute force (every triangle, watertight double-precision test; the test oracle). Both
/// cast against the triangles of occluding objects only: see-through ones do not stop rays.
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>

#include "viewcells/core/vec3.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// A ray o + t*d for t in [tnear, tfar]. d need not be normalised; t is in units of |d|.
struct Ray {
  Vec3 origin;
  Vec3 dir;
  double tnear = 0.0;
  double tfar = std::numeric_limits<double>::infinity();
};

struct Hit {
  double t = std::numeric_limits<double>::infinity();
  uint32_t triangle = kNoObject;
  uint32_t object = kNoObject;
  bool front = false;  ///< the ray hit the side the triangle normal points to
  bool hit() const { return triangle != kNoObject; }
};

/// Front face test shared by every caster: dot(normal, dir) < 0 in double precision.
inline bool is_front_face(const Scene& scene, uint32_t triangle, const Vec3& dir) {
  return dot(scene.triangle_normal(triangle), dir) < 0.0;
}

class RayCaster {
 public:
  virtual ~RayCaster() = default;
  /// Closest hit of every ray; hits.size() == rays.size(). Thread-safe; call it from many
  /// threads on disjoint spans.
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits) const = 0;
  Hit intersect(const Ray& ray) const {
    Hit h;
    intersect(std::span<const Ray>(&ray, 1), std::span<Hit>(&h, 1));
    return h;
  }
  /// Forward and backward closest hits from each origin: hits[2i] along dirs[i], hits[2i+1]
  /// along -dirs[i] (t in [0, inf)). The sampler's hot path; implementations may skip
  /// building Ray structs. hits.size() == 2 * origins.size().
  virtual void intersect_pairs(std::span<const Vec3> origins, std::span<const Vec3> dirs, std::span<Hit> hits) const;
  /// As intersect(), for rays that run side by side (a camera's pixels, given tile by tile, 16
  /// neighbours at a time): Embree casts them as packets (rtcIntersect16, coherent), several
  /// times cheaper a ray than incoherent ones. The same hits up to the kernels' last bits.
  virtual void intersect_coherent(std::span<const Ray> rays, std::span<Hit> hits) const { intersect(rays, hits); }
  /// Casts the rays through the underlying engine alone, in parallel, with conversion to its
  /// native format done beforehand; returns the seconds spent casting (for --measure-raw).
  virtual double time_raw(std::span<const Ray> rays) const = 0;
  virtual std::string name() const = 0;
};

struct EmbreeConfig {
  /// RTC_SCENE_FLAG_ROBUST: fewer rays leak through shared edges, somewhat slower.
  bool robust = true;
  /// RTC_BUILD_QUALITY_HIGH: slower BVH build, faster rays; worth it for millions of rays.
  bool high_quality_build = true;
  /// Which triangles: those of occluding objects (what stops rays: the default), or those of
  /// the see-through ones (ObjectInfo::occluder false), to find where segments cross them.
  bool see_through = false;
  /// Embree's instruction set: "" for embree_isa() (VIEWCELLS_EMBREE_ISA, else the CPU's best),
  /// or one of "sse2", "sse4.2", "avx", "avx2", "avx512". Embree's kernels differ in the last
  /// bits of their hits, so sampled results are identical across machines only for one ISA.
  std::string isa;
};


/// Builds the Embree BVH (in a local frame centred on the scene, so float precision holds
/// for coordinates around 1e5). Throws Error when Embree reports an error or when no
/// triangle is selected.
std::unique_ptr<RayCaster> make_embree_caster(const Scene& scene, const EmbreeConfig& config = {});

/// O(triangles) per ray; for tests and as an oracle only. The scene must outlive the caster.
std::unique_ptr<RayCaster> make_brute_force_caster(const Scene& scene);

}  // namespace viewcells
