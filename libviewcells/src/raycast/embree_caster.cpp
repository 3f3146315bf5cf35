// Embree 3 ray caster. The BVH is built in a local frame centred on the scene bounds: Embree
// works in float, and a city at 1e5 would otherwise lose centimetres. Hit distances come back
// in float; callers rebuild hit points in double from their double-precision rays.
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <sstream>
#include <vector>

#include "viewcells/core/error.h"
#include "viewcells/core/isa.h"
#include "viewcells/raycast/ray_caster.h"

namespace viewcells {
namespace {

const char* error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error";
}

/// The device's error callback keeps the message; check() turns it into an exception.
struct ErrorSink {
  std::mutex mutex;
  std::string message;
};

void error_callback(void* user, RTCError code, const char* str) {
  auto* sink = static_cast<ErrorSink*>(user);
  std::lock_guard lock(sink->mutex);
  if (sink->message.empty()) sink->message = std::string(error_name(code)) + (str ? std::string(": ") + str : "");
}

constexpr unsigned kChunk = 64;  // rays per rtcIntersect1M call

/// Embree's Ray::valid() bound on origins and directions (FLT_LARGE in its sources); a ray
/// beyond it trips an assertion in Debian's build, so it is refused before it gets there.
constexpr double kEmbreeLargest = 1.8e18;

/// Largest |coordinate - centre| of the scene's vertices and the vertex that reaches it.
std::pair<double, size_t> farthest_vertex(const Scene& scene, const Vec3& center) {
  double r = 0;
  size_t at = 0;
  for (size_t i = 0; i < scene.vertices.size(); ++i) {
    const Vec3 d = scene.vertices[i] - center;
    const double m = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    if (!(m <= r)) r = m, at = i;  // NaN-safe: a NaN distance is taken as the farthest
  }
  return {r, at};
}

/// Embree holds vertices in single precision, relative to the scene's centre. Refuses a scene
/// whose extent makes single precision coarser than a hundredth of its median triangle edge
/// (a stray triangle far away, or coordinates beyond float range): rays would leak or miss.
void check_float_precision(const Scene& scene, const Vec3& center) {
  const auto [reach, at] = farthest_vertex(scene, center);
  std::vector<double> edges;
  edges.reserve(scene.triangles.size());
  for (const auto& t : scene.triangles) {
    const Vec3 &a = scene.vertices[t[0]], &b = scene.vertices[t[1]], &c = scene.vertices[t[2]];
    edges.push_back(std::max({length(b - a), length(c - b), length(a - c)}));
  }
  std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
  const double median_edge = edges[edges.size() / 2];
  const double resolution = reach * std::ldexp(1.0, -23);  // float spacing at that distance
  if (reach < kEmbreeLargest / 2 && resolution <= 0.01 * median_edge) return;
  uint32_t object = kNoObject;
  for (size_t t = 0; t < scene.triangles.size() && object == kNoObject; ++t)
    for (uint32_t v : scene.triangles[t])
      if (v == at) object = scene.triangle_object[t];
  const Vec3& p = scene.vertices[at];
  std::ostringstream msg;
  msg.precision(6);
  msg << "coordinates reach " << reach << " from the scene's centre, where single precision (Embree) resolves only "
      << resolution << ", but the median triangle edge is " << median_edge << ": rays would leak or miss. "
      << "The farthest vertex is (" << p.x << ", " << p.y << ", " << p.z << ")";
  if (object != kNoObject) msg << " of object '" << scene.objects[object].name << "'";
  msg << "; remove stray geometry, or split the scene into parts that single precision can hold";
  throw Error(scene.source, 0, msg.str());
}

[[noreturn]] void invalid_ray(const Vec3& origin, const Vec3& dir, double tnear, double tfar) {
  std::ostringstream msg;
  msg.precision(17);
  msg << "invalid ray for Embree: origin (" << origin.x << ", " << origin.y << ", " << origin.z << "), direction ("
      << dir.x << ", " << dir.y << ", " << dir.z << "), t in [" << tnear << ", " << tfar
      << "]: origins must lie within " << kEmbreeLargest
      << " of the scene's centre and every value must be finite (is the view box far outside the scene?)";
  throw Error(msg.str());
}

class EmbreeCaster final : public RayCaster {
 public:
  EmbreeCaster(const Scene& scene, const EmbreeConfig& config) : scene_(scene), config_(config) {
    center_ = scene.bounds.empty() ? Vec3{} : scene.bounds.center();
    for (uint32_t t = 0; t < scene.triangles.size(); ++t)
      if (scene.objects[scene.triangle_object[t]].occluder != config.see_through) selected_.push_back(t);
    if (selected_.empty())
      throw Error(config.see_through ? "the scene has no see-through triangles" : "the scene has no occluding triangles");
    if (selected_.size() == scene.triangles.size()) selected_.clear();  // all: primitive = triangle
    check_float_precision(scene, center_);
    isa_ = config.isa.empty() ? embree_isa() : checked_embree_isa(config.isa);
    device_ = rtcNewDevice(("verbose=0,isa=" + isa_).c_str());
    if (!device_) throw Error(std::string("embree: cannot create device: ") + error_name(rtcGetDeviceError(nullptr)));
    rtcSetDeviceErrorFunction(device_, error_callback, &sink_);
    try {
      build();
    } catch (...) {
      release();
      throw;
    }
  }
  ~EmbreeCaster() override { release(); }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override {
    RTCRayHit native[kChunk];
    for (size_t start = 0; start < rays.size(); start += kChunk) {
      const unsigned n = static_cast<unsigned>(std::min<size_t>(kChunk, rays.size() - start));
      for (unsigned i = 0; i < n; ++i) to_native(rays[start + i].origin, rays[start + i].dir, rays[start + i].tnear,
                                                 rays[start + i].tfar, native[i]);
      cast(native, n);
      from_native(native, n, hits.data() + start);
    }
  }

  void intersect_pairs(std::span<const Vec3> origins, std::span<const Vec3> dirs, std::span<Hit> hits) const override {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    RTCRayHit native[kChunk];
    for (size_t start = 0; start < origins.size(); start += kChunk / 2) {
      const unsigned n = static_cast<unsigned>(std::min<size_t>(kChunk / 2, origins.size() - start));
      for (unsigned i = 0; i < n; ++i) {
        to_native(origins[start + i], dirs[start + i], 0.0, kInf, native[2 * i]);
        native[2 * i + 1] = native[2 * i];
        native[2 * i + 1].ray.dir_x = -native[2 * i].ray.dir_x;
        native[2 * i + 1].ray.dir_y = -native[2 * i].ray.dir_y;
        native[2 * i + 1].ray.dir_z = -native[2 * i].ray.dir_z;
      }
      cast(native, 2 * n);
      from_native(native, 2 * n, hits.data() + 2 * start);
    }
  }

  void intersect_coherent(std::span<const Ray> rays, std::span<Hit> hits) const override {
    constexpr unsigned K = 16;
    alignas(64) RTCRayHit16 packet;
    alignas(64) int valid[K];
    RTCRayHit native[K];
    for (size_t start = 0; start < rays.size(); start += K) {
      const unsigned n = static_cast<unsigned>(std::min<size_t>(K, rays.size() - start));
      for (unsigned i = 0; i < n; ++i)
        to_native(rays[start + i].origin, rays[start + i].dir, rays[start + i].tnear, rays[start + i].tfar, native[i]);
      for (unsigned i = 0; i < K; ++i) {
        const RTCRay& r = native[i < n ? i : 0].ray;  // idle lanes copy a valid ray, and are masked off
        valid[i] = i < n ? -1 : 0;
        packet.ray.org_x[i] = r.org_x;
        packet.ray.org_y[i] = r.org_y;
        packet.ray.org_z[i] = r.org_z;
        packet.ray.dir_x[i] = r.dir_x;
        packet.ray.dir_y[i] = r.dir_y;
        packet.ray.dir_z[i] = r.dir_z;
        packet.ray.tnear[i] = r.tnear;
        packet.ray.tfar[i] = r.tfar;
        packet.ray.time[i] = 0.0f;
        packet.ray.mask[i] = 0xffffffffu;
        packet.ray.id[i] = i;
        packet.ray.flags[i] = 0;
        packet.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
      }
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      rtcIntersect16(valid, rtc_scene_, &context, &packet);
      for (unsigned i = 0; i < n; ++i) {
        native[i].ray.tfar = packet.ray.tfar[i];
        native[i].hit.geomID = packet.hit.geomID[i];
        native[i].hit.primID = packet.hit.primID[i];
        native[i].hit.Ng_x = packet.hit.Ng_x[i];
        native[i].hit.Ng_y = packet.hit.Ng_y[i];
        native[i].hit.Ng_z = packet.hit.Ng_z[i];
      }
      from_native(native, n, hits.data() + start);
    }
  }

  double time_raw(std::span<const Ray> rays) const override {
    std::vector<RTCRayHit> native(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) to_native(rays[i].origin, rays[i].dir, rays[i].tnear, rays[i].tfar, native[i]);
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, native.size(), 2048),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t s = r.begin(); s < r.end(); s += kChunk)
                          cast(native.data() + s, static_cast<unsigned>(std::min<size_t>(kChunk, r.end() - s)));
                      });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    check("rtcIntersect1M");
    return seconds;
  }

  std::string name() const override {
    return std::string("embree ") + isa_ + (config_.robust ? " robust" : " fast") + (config_.see_through ? " see-through" : "");
  }

 private:
  size_t primitive_count() const { return selected_.empty() ? scene_.triangles.size() : selected_.size(); }

  void build() {
    rtc_scene_ = rtcNewScene(device_);
    check("rtcNewScene");
    rtcSetSceneFlags(rtc_scene_, config_.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(rtc_scene_, config_.high_quality_build ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    check("rtcNewGeometry");
    auto* verts = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), scene_.vertices.size()));
    auto* index = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), primitive_count()));
    if (!verts || !index) {
      rtcReleaseGeometry(geom);
      check("rtcSetNewGeometryBuffer");
      throw Error("embree: cannot allocate geometry buffers");
    }
    for (size_t i = 0; i < scene_.vertices.size(); ++i) {
      const Vec3 p = scene_.vertices[i] - center_;
      verts[3 * i] = static_cast<float>(p.x);
      verts[3 * i + 1] = static_cast<float>(p.y);
      verts[3 * i + 2] = static_cast<float>(p.z);
    }
    for (size_t p = 0; p < primitive_count(); ++p)
      for (int k = 0; k < 3; ++k) index[3 * p + k] = scene_.triangles[selected_.empty() ? p : selected_[p]][k];
    rtcCommitGeometry(geom);
    rtcAttachGeometry(rtc_scene_, geom);
    rtcReleaseGeometry(geom);
    check("rtcAttachGeometry");
    rtcCommitScene(rtc_scene_);
    check("rtcCommitScene");
  }

  void release() {
    if (rtc_scene_) rtcReleaseScene(rtc_scene_);
    if (device_) rtcReleaseDevice(device_);
    rtc_scene_ = nullptr;
    device_ = nullptr;
  }

  void check(const char* where) const {
    const RTCError e = rtcGetDeviceError(device_);
    std::lock_guard lock(sink_.mutex);
    if (e == RTC_ERROR_NONE && sink_.message.empty()) return;
    const std::string msg = sink_.message.empty() ? error_name(e) : sink_.message;
    sink_.message.clear();
    throw Error(std::string("embree: ") + where + ": " + msg);
  }

  void to_native(const Vec3& origin, const Vec3& dir, double tnear, double tfar, RTCRayHit& rh) const {
    const Vec3 o = origin - center_;
    // Written so that NaN fails every comparison and lands in the error.
    const bool ok = std::abs(o.x) < kEmbreeLargest && std::abs(o.y) < kEmbreeLargest && std::abs(o.z) < kEmbreeLargest &&
                    std::abs(dir.x) < kEmbreeLargest && std::abs(dir.y) < kEmbreeLargest &&
                    std::abs(dir.z) < kEmbreeLargest && tnear >= 0 && tfar >= tnear;
    if (!ok) [[unlikely]]
      invalid_ray(origin, dir, tnear, tfar);
    rh.ray.org_x = static_cast<float>(o.x);
    rh.ray.org_y = static_cast<float>(o.y);
    rh.ray.org_z = static_cast<float>(o.z);
    rh.ray.dir_x = static_cast<float>(dir.x);
    rh.ray.dir_y = static_cast<float>(dir.y);
    rh.ray.dir_z = static_cast<float>(dir.z);
    rh.ray.tnear = static_cast<float>(tnear);
    rh.ray.tfar = static_cast<float>(tfar);
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }

  void from_native(const RTCRayHit* native, unsigned n, Hit* hits) const {
    // The object of a hit triangle is a read from a table of megabytes: a cache miss each.
    // Ask for all of them first, so that the misses overlap instead of queueing.
    const uint32_t* object_of = scene_.triangle_object.data();
    const bool all = selected_.empty();
    for (unsigned i = 0; i < n; ++i)
      if (native[i].hit.geomID != RTC_INVALID_GEOMETRY_ID && all) __builtin_prefetch(object_of + native[i].hit.primID);
    for (unsigned i = 0; i < n; ++i) {
      const RTCRayHit& rh = native[i];
      Hit& h = hits[i];
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        h = Hit{};
        continue;
      }
      h.t = rh.ray.tfar;
      h.triangle = all ? rh.hit.primID : selected_[rh.hit.primID];
      h.object = object_of[h.triangle];
      // Embree's Ng is (v1-v0)x(v2-v0) like Scene::triangle_normal (checked against the oracle);
      // using it avoids reading three vertices from random memory per hit.
      h.front = rh.hit.Ng_x * rh.ray.dir_x + rh.hit.Ng_y * rh.ray.dir_y + rh.hit.Ng_z * rh.ray.dir_z < 0.0f;
    }
  }

  void cast(RTCRayHit* rays, unsigned n) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    rtcIntersect1M(rtc_scene_, &context, rays, n, sizeof(RTCRayHit));
  }

  const Scene& scene_;
  EmbreeConfig config_;
  std::vector<uint32_t> selected_;  ///< the triangle of each primitive; empty when all are
  Vec3 center_;
  std::string isa_;
  RTCDevice device_ = nullptr;
  RTCScene rtc_scene_ = nullptr;
  mutable ErrorSink sink_;
};

}  // namespace

std::unique_ptr<RayCaster> make_embree_caster(const Scene& scene, const EmbreeConfig& config) {
  if (scene.triangles.empty()) throw Error("cannot build a ray caster for an empty scene");
  return std::make_unique<EmbreeCaster>(scene, config);
}

}  // namespace viewcells
