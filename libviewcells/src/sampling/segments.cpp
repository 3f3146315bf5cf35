/// Visibility segments (view-cell-construction paper, section 4.1) as arrays, and the .vseg file.
#include "viewcells/sampling/segments.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#ifdef __linux__
#include <sys/mman.h>
#endif

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"

namespace viewcells {

namespace {

/// The low 10 bits of v, one every sixth bit (the Z-order of two 3D points).
uint64_t spread6(uint64_t v) {
  uint64_t out = 0;
  for (int bit = 0; bit < 10; ++bit) out |= ((v >> bit) & 1) << (6 * bit);
  return out;
}

}  // namespace

std::vector<size_t> coherent_order(const SegmentSet& s, const Box3& box) {
  std::array<std::array<uint64_t, 1024>, 6> table;  // per coordinate: spread6 of its cell, placed
  for (int k = 0; k < 6; ++k)
    for (uint64_t v = 0; v < 1024; ++v) table[k][v] = spread6(v) << (5 - k);
  const Vec3 lo = box.lo, size = box.hi - box.lo;
  auto cell = [&](double v, int axis) {  // 0..1023 along `axis` of the box; outside or NaN: clamped
    const double u = (v - lo[axis]) / size[axis] * 1024.0;
    return u >= 1023.0 ? uint64_t{1023} : (u >= 0.0 ? static_cast<uint64_t>(u) : uint64_t{0});
  };
  std::vector<std::pair<uint64_t, size_t>> keyed(s.size());
  tbb::parallel_for(size_t{0}, s.size(), [&](size_t i) {
    const double c[6] = {s.ax[i], s.ay[i], s.az[i], s.bx[i], s.by[i], s.bz[i]};
    uint64_t key = 0;
    for (int k = 0; k < 6; ++k) key |= table[k][cell(c[k], k % 3)];
    keyed[i] = {key, i};
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<size_t> order(s.size());
  tbb::parallel_for(size_t{0}, s.size(), [&](size_t i) { order[i] = keyed[i].second; });
  return order;
}

void SegmentSet::reserve(size_t n) {
  for (auto* v : {&ax, &ay, &az, &bx, &by, &bz}) v->reserve(n);
  for (auto* v : {&object_a, &object_b, &triangle_a, &triangle_b}) v->reserve(n);
}

void SegmentSet::resize(size_t n) {
  for (auto* v : {&ax, &ay, &az, &bx, &by, &bz}) v->resize(n);
  for (auto* v : {&object_a, &object_b, &triangle_a, &triangle_b}) v->resize(n);
}

void SegmentSet::reserve_for_output(size_t n) {
  reserve(n);
#ifdef __linux__
  // Ask for transparent huge pages before the arrays are touched: a few hundred faults of
  // 2 MB instead of tens of thousands of 4 KB ones for an output of hundreds of megabytes.
  auto advise = [n](const void* p, size_t elem) {
    const uintptr_t page = 4096, begin = (reinterpret_cast<uintptr_t>(p) + page - 1) & ~(page - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + n * elem) & ~(page - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // a hint
  };
  for (auto* v : {&ax, &ay, &az, &bx, &by, &bz}) advise(v->data(), sizeof(double));
  for (auto* v : {&object_a, &object_b, &triangle_a, &triangle_b}) advise(v->data(), sizeof(uint32_t));
#endif
}

void SegmentSet::push_back(const Vec3& a, const Vec3& b, uint32_t oa, uint32_t ob, uint32_t ta, uint32_t tb) {
  ax.push_back(a.x);
  ay.push_back(a.y);
  az.push_back(a.z);
  bx.push_back(b.x);
  by.push_back(b.y);
  bz.push_back(b.z);
  object_a.push_back(oa);
  object_b.push_back(ob);
  triangle_a.push_back(ta);
  triangle_b.push_back(tb);
}

void SegmentSet::append(const SegmentSet& o) { append(o, 0, o.size()); }

void SegmentSet::append(const SegmentSet& o, size_t first, size_t n) {
  auto add = [&](auto& to, const auto& from) { to.insert(to.end(), from.begin() + first, from.begin() + first + n); };
  add(ax, o.ax);
  add(ay, o.ay);
  add(az, o.az);
  add(bx, o.bx);
  add(by, o.by);
  add(bz, o.bz);
  add(object_a, o.object_a);
  add(object_b, o.object_b);
  add(triangle_a, o.triangle_a);
  add(triangle_b, o.triangle_b);
}

bool SegmentSet::operator==(const SegmentSet& o) const {
  return view_box == o.view_box && ax == o.ax && ay == o.ay && az == o.az && bx == o.bx && by == o.by &&
         bz == o.bz && object_a == o.object_a && object_b == o.object_b && triangle_a == o.triangle_a &&
         triangle_b == o.triangle_b;
}

namespace {
constexpr char kMagic[5] = "VSEG";
constexpr uint32_t kVersion = 1;  // layout: header, 6 coordinate arrays, objects a/b, triangles a/b
}  // namespace

void write_segments(const std::string& path, const SegmentSet& s, const SegmentFileHeader& h) {
  ByteWriter w;
  w.put(s.view_box.lo);
  w.put(s.view_box.hi);
  w.put<uint64_t>(h.seed);
  w.put<uint64_t>(h.samples);
  w.put<uint64_t>(h.scene_fingerprint);
  w.put<uint32_t>(h.object_count);
  w.put<uint8_t>(h.empty_space_detection ? 1 : 0);
  put_segments(w, s);
  write_container(path, kMagic, kVersion, w.data());
}

SegmentSet read_segments(const std::string& path, SegmentFileHeader* header) {
  uint32_t version = 0;
  const std::string payload = read_container(path, kMagic, kVersion, version);
  ByteReader r(payload, path);
  SegmentSet s;
  SegmentFileHeader h;
  s.view_box.lo = r.get<Vec3>();
  s.view_box.hi = r.get<Vec3>();
  h.seed = r.get<uint64_t>();
  h.samples = r.get<uint64_t>();
  h.scene_fingerprint = r.get<uint64_t>();
  h.object_count = r.get<uint32_t>();
  h.empty_space_detection = r.get<uint8_t>() != 0;
  get_segments(r, s, payload.size() / sizeof(uint32_t));
  if (!r.at_end()) r.fail("trailing bytes after the segment arrays");
  const size_t n = s.size();
  if (s.view_box.empty() || !is_finite(s.view_box.lo) || !is_finite(s.view_box.hi)) r.fail("invalid view box");
  for (size_t i = 0; i < n; ++i) {
    if (!s.view_box.contains(s.a(i)) || !s.view_box.contains(s.b(i)))
      r.fail("segment " + std::to_string(i) + " lies outside the view box or is not finite");
    for (uint32_t o : {s.object_a[i], s.object_b[i]})
      if (o != kNoObject && o >= h.object_count)
        r.fail("segment " + std::to_string(i) + " names object " + std::to_string(o) + " of " +
               std::to_string(h.object_count));
    if ((s.object_a[i] == kNoObject) != (s.triangle_a[i] == kNoObject) ||
        (s.object_b[i] == kNoObject) != (s.triangle_b[i] == kNoObject))
      r.fail("segment " + std::to_string(i) + " has an object without a triangle or the reverse");
    if (s.object_a[i] == kNoObject && s.object_b[i] == kNoObject)
      r.fail("segment " + std::to_string(i) + " sees no object");
  }
  if (header) *header = h;
  return s;
}

void put_segments(ByteWriter& w, const SegmentSet& s) {
  for (const auto* v : {&s.ax, &s.ay, &s.az, &s.bx, &s.by, &s.bz}) w.put_array(*v);
  for (const auto* v : {&s.object_a, &s.object_b, &s.triangle_a, &s.triangle_b}) w.put_array(*v);
}

void get_segments(ByteReader& r, SegmentSet& s, uint64_t max_count) {
  for (auto* v : {&s.ax, &s.ay, &s.az, &s.bx, &s.by, &s.bz}) r.get_array(*v, max_count);
  for (auto* v : {&s.object_a, &s.object_b, &s.triangle_a, &s.triangle_b}) r.get_array(*v, max_count);
  const size_t n = s.ax.size();
  for (const auto* v : {&s.ay, &s.az, &s.bx, &s.by, &s.bz})
    if (v->size() != n) r.fail("segment arrays differ in length");
  if (s.object_a.size() != n || s.object_b.size() != n || s.triangle_a.size() != n || s.triangle_b.size() != n)
    r.fail("object or triangle arrays differ in length");
}

}  // namespace viewcells
