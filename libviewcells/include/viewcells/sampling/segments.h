#pragma once
/// Visibility segments (view-cell-construction paper, section 4.1), stored as a structure of
/// arrays: endpoints a and b in double precision, inside the view space box, and the object
/// seen at each end (kNoObject where the segment left the scene unhit and was clipped).
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/default_init.h"
#include "viewcells/core/vec3.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

struct SegmentSet {
  Box3 view_box;
  // Uninitialised growth: resize() of a fresh output costs no memset.
  RawVector<double> ax, ay, az, bx, by, bz;
  RawVector<uint32_t> object_a, object_b;
  RawVector<uint32_t> triangle_a, triangle_b;  ///< the triangle hit at each end, or kNoObject

  size_t size() const { return ax.size(); }
  Vec3 a(size_t i) const { return {ax[i], ay[i], az[i]}; }
  Vec3 b(size_t i) const { return {bx[i], by[i], bz[i]}; }
  void reserve(size_t n);
  void resize(size_t n);
  /// reserve(n) for an output about to be appended to: on Linux, also asks for transparent
  /// huge pages, which saves most page faults on arrays of hundreds of megabytes.
  void reserve_for_output(size_t n);
  void push_back(const Vec3& a, const Vec3& b, uint32_t oa, uint32_t ob, uint32_t ta = kNoObject,
                 uint32_t tb = kNoObject);
  void set(size_t i, const Vec3& a, const Vec3& b, uint32_t oa, uint32_t ob, uint32_t ta, uint32_t tb) {
    ax[i] = a.x, ay[i] = a.y, az[i] = a.z, bx[i] = b.x, by[i] = b.y, bz[i] = b.z;
    object_a[i] = oa, object_b[i] = ob;
    triangle_a[i] = ta, triangle_b[i] = tb;
  }
  /// Appends all of `o` (view boxes must match).
  void append(const SegmentSet& o);
  /// Appends segments [first, first + n) of `o`.
  void append(const SegmentSet& o, size_t first, size_t n);
  bool operator==(const SegmentSet& o) const;
  /// Bytes used by the arrays.
  size_t memory_bytes() const { return size() * (6 * sizeof(double) + 4 * sizeof(uint32_t)); }
};

/// The segments' indices in an order where neighbours have both ends near each other (the
/// Z-order of their ends, 10 bits an axis within `box`, interleaved): walked down a tree in
/// this order, consecutive segments visit mostly the same nodes and leaves, which are then in
/// the cache. Sampled segments come in random order, so walking them as drawn misses on almost
/// every node of a large tree. Only an order: any result that does not depend on the order of
/// the segments is the same.
std::vector<size_t> coherent_order(const SegmentSet& s, const Box3& box);

/// What a segment file records besides the segments.
/// The segment arrays of `s`, as a .vseg file and a message between ranks (core/ranks.h)
/// hold them, and back: get_segments replaces the segments of `s` (its view box stays) and
/// fails (ByteReader::fail) on arrays of different lengths or more than max_count elements.
void put_segments(ByteWriter& w, const SegmentSet& s);
void get_segments(ByteReader& r, SegmentSet& s, uint64_t max_count);

struct SegmentFileHeader {
  uint64_t seed = 0;
  uint64_t samples = 0;            ///< samples drawn (valid or not)
  uint64_t scene_fingerprint = 0;  ///< Scene::fingerprint() of the scene sampled
  uint32_t object_count = 0;
  bool empty_space_detection = false;
};

/// Writes a versioned, checksummed, zstd-compressed `.vseg` file (atomically).
void write_segments(const std::string& path, const SegmentSet& segments, const SegmentFileHeader& header);
/// Reads a `.vseg` file; rejects corrupt, truncated or inconsistent files with an Error.
SegmentSet read_segments(const std::string& path, SegmentFileHeader* header = nullptr);

}  // namespace viewcells
