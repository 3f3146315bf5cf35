// The runtime reader for engines (runtime/) against the toolkit's own reading of the same
// .pvs files: same cells, same visible sets, same point location, also for points on and a
// few ulps off geometry-aligned planes, where only an exact predicate gets the side right.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "viewcells/format/id_lists.h"
#include "support/test_scenes.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/rng.h"
#include "viewcells/merge/merge.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/runtime.hpp"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

/// A .pvs of `count` view cells of a rotated office (its planes are not axis-aligned).
struct Level {
  PvsFile file;
  std::string path;
};

const Level& level() {
  static const Level l = [] {
    const Scene scene = generate_scene({GeneratorKind::kRotatedOffice, 1, 1});
    const SegmentSet segs = test::sample_scene(scene, 20000);
    SubdivisionConfig config;
    config.max_cells = 150;
    config.show_progress = false;
    config.geometry_aligned = GeometryAlignedMode::kOn;
    const Subdivision s = subdivide(scene, segs, CostModel{}, config);
    const auto leaf = leaf_pvs(s, segs);
    MergeConfig mc;
    mc.show_progress = false;
    const MergeHistory h = merge_cells(scene, partition_from_subdivision(s, leaf), CostModel{}, mc);
    Level out;
    out.file = make_pvs_file(s, leaf, h, extract_by_count(h, 40).cells);
    out.file.object_count = static_cast<uint32_t>(scene.object_count());
    for (const ObjectInfo& o : scene.objects) out.file.object_names.push_back(o.name);
    out.file.scene_fingerprint = scene.fingerprint();
    out.file.rule = "40 cells (count)";
    out.path = test::temp_path("runtime.pvs");
    write_pvs(out.path, out.file);
    return out;
  }();
  return l;
}

TEST(Runtime, ReadsWhatTheToolkitWrites) {
  const Level& l = level();
  const runtime::PvsFile r(l.path);
  ASSERT_EQ(r.cell_count(), l.file.pvs.cell_count);
  EXPECT_EQ(r.object_count(), l.file.object_count);
  EXPECT_EQ(r.scene_fingerprint(), l.file.scene_fingerprint);
  EXPECT_EQ(r.rule(), "40 cells (count)");
  EXPECT_EQ(r.row_bytes(), (l.file.object_count + 7) / 8);
  for (uint32_t o = 0; o < l.file.object_count; ++o) EXPECT_EQ(r.object_name(o), l.file.object_names[o]);
  EXPECT_EQ(r.object_name(l.file.object_count), "");
  for (uint32_t c = 0; c < r.cell_count(); ++c) {
    const std::vector<uint32_t> want = l.file.pvs.cell_pvs(c);
    const runtime::ObjectList got = r.objects(static_cast<int32_t>(c));
    EXPECT_EQ(std::vector<uint32_t>(got.begin(), got.end()), want) << "cell " << c;
    const std::vector<uint8_t> bits = r.bits(static_cast<int32_t>(c));
    for (uint32_t o = 0; o < l.file.object_count; ++o) {
      const bool in = std::binary_search(want.begin(), want.end(), o);
      EXPECT_EQ(((bits[o >> 3] >> (o & 7)) & 1) != 0, in);
      EXPECT_EQ(r.sees(static_cast<int32_t>(c), o), in);
    }
  }
  EXPECT_TRUE(r.objects(-1).empty());
  EXPECT_TRUE(r.objects(static_cast<int32_t>(r.cell_count())).empty());
  EXPECT_THROW(r.bits(-1), std::out_of_range);
  uint8_t small = 0;
  EXPECT_EQ(vc_pvs_cell_bits(r.handle(), 0, &small, 0), -1);
  EXPECT_GT(r.memory_bytes(), 4 * l.file.pvs.stored_entries());
  // The file's bytes opened from memory answer the same as the file, and a null buffer is refused.
  std::ifstream in(l.path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  vc_pvs* m = nullptr;
  ASSERT_EQ(vc_pvs_open_memory(bytes.data(), bytes.size(), 0, &m, nullptr, 0), 0);
  ASSERT_EQ(vc_pvs_cell_count(m), r.cell_count());
  for (uint32_t c = 0; c < r.cell_count(); ++c) EXPECT_EQ(r.bits(static_cast<int32_t>(c)), [&] {
      std::vector<uint8_t> row(r.row_bytes());
      vc_pvs_cell_bits(m, static_cast<int32_t>(c), row.data(), row.size());
      return row;
    }()) << "cell " << c;
  vc_pvs_close(m);
  char error[128] = "";
  EXPECT_NE(vc_pvs_open_memory(nullptr, 0, 0, &m, error, sizeof error), 0);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(error).find("NULL"), std::string::npos) << error;
}

TEST(Runtime, LocatesLikeTheToolkitOnAndNearEveryPlane) {
  const Level& l = level();
  const runtime::PvsFile r(l.path);
  const Box3& box = l.file.bsp.view_box;
  Rng rng(5);
  for (int k = 0; k < 20000; ++k) {
    const Vec3 p{rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y), rng.uniform(box.lo.z, box.hi.z)};
    const int32_t cell = l.file.locate(p);
    ASSERT_EQ(r.locate(p.x, p.y, p.z), cell) << p.x << " " << p.y << " " << p.z;
    int32_t at = -2;
    const runtime::ObjectList seen = r.objects_at(p.x, p.y, p.z, &at);
    ASSERT_EQ(at, cell);
    ASSERT_EQ(seen.data, r.objects(cell).data);
    ASSERT_EQ(seen.size, r.objects(cell).size);
  }
  int32_t outside = 0;
  EXPECT_TRUE(r.objects_at(box.lo.x - 1, box.lo.y, box.lo.z, &outside).empty());
  EXPECT_EQ(outside, -1);
  // Points on each plane (rounded onto it), and a few ulps to either side: the float filter
  // cannot decide these, and the exact fallback must agree with CGAL's predicate.
  size_t general = 0, checked = 0;
  for (const Plane& pl : l.file.bsp.planes) {
    if (pl.is_axis_aligned()) {
      const Vec3 c = box.center();
      for (double d : {0.0, 1e-12, -1e-12}) {
        Vec3 p = c;
        p[pl.axis] = pl.offset + d;
        if (!box.contains(p)) continue;
        ASSERT_EQ(r.locate(p.x, p.y, p.z), l.file.locate(p));
      }
      continue;
    }
    ++general;
    const auto& q = pl.points;
    for (int k = 0; k < 200; ++k) {
      const double s = rng.uniform(-2, 2), t = rng.uniform(-2, 2);
      Vec3 p = q[0] + s * (q[1] - q[0]) + t * (q[2] - q[0]);
      for (int ulps = -3; ulps <= 3; ++ulps) {
        Vec3 v = p;
        for (int i = 0; i < std::abs(ulps); ++i) v.x = std::nextafter(v.x, ulps > 0 ? 1e300 : -1e300);
        if (!box.contains(v)) continue;
        ++checked;
        ASSERT_EQ(r.locate(v.x, v.y, v.z), l.file.locate(v)) << "plane point " << v.x << " " << v.y << " " << v.z;
      }
    }
    for (const Vec3& v : q) {
      if (!box.contains(v)) continue;
      ASSERT_EQ(r.locate(v.x, v.y, v.z), l.file.locate(v));
    }
  }
  EXPECT_GT(general, 0u) << "the rotated office should need geometry-aligned planes";
  EXPECT_GT(checked, 100u);
  EXPECT_EQ(r.locate(box.hi.x + 1, box.lo.y, box.lo.z), -1);
  EXPECT_EQ(r.locate(NAN, box.lo.y, box.lo.z), -1);
  EXPECT_EQ(r.locate(box.lo.x, box.lo.y, box.lo.z), l.file.locate(box.lo));
  EXPECT_EQ(r.locate(box.hi.x, box.hi.y, box.hi.z), l.file.locate(box.hi));
}

/// A .pvs of two cells split by the plane through a, b, c, in the view box [lo, hi].
std::string two_cell_file(const Vec3& a, const Vec3& b, const Vec3& c, const Box3& box, const std::string& name) {
  PvsFile f;
  f.bsp.view_box = box;
  for (int axis = 0; axis < 3; ++axis) {
    f.bsp.planes.push_back(Plane::axis_aligned(axis, box.lo[axis]));
    f.bsp.planes.push_back(Plane::axis_aligned(axis, box.hi[axis]));
  }
  Plane p;
  p.normal = {0, 0, 1};  // not used to decide sides: the points are
  p.points = {a, b, c};
  f.bsp.planes.push_back(p);
  f.bsp.nodes.resize(3);
  f.bsp.nodes[0].plane = 6;
  f.bsp.nodes[0].child[0] = 1;
  f.bsp.nodes[0].child[1] = 2;
  f.bsp.nodes[1].parent = f.bsp.nodes[2].parent = 0;
  f.leaf_cell = {-1, 0, 1};
  f.cell_mht_node = {0, 1};
  f.object_count = 2;
  f.pvs.cell_count = 2;
  f.pvs.parent = {-1, -1};
  f.pvs.stored = {{0}, {1}};
  const std::string path = test::temp_path(name);
  write_pvs(path, f);
  return path;
}

TEST(Runtime, LocatesLikeTheToolkitAtAnyMagnitude) {
  // Points whose products overflow or underflow double (1e136 cubed, 1e-104 cubed): the
  // filter cannot decide, and the exact fallback must still agree with CGAL. A fuzzed file
  // with a view box at 1e136 found the first.
  Rng rng(11);
  size_t checked = 0;
  for (double s : {1e-104, 1e-100, 1e-10, 1.0, 1e10, 1e100, 1e136, 1e150}) {
    const Vec3 a{0.1 * s, -0.3 * s, 0.2 * s}, b{0.9 * s, 0.2 * s, -0.1 * s}, c{-0.2 * s, 0.8 * s, 0.3 * s};
    const Box3 box{{-s, -s, -s}, {s, s, s}};
    const std::string path = two_cell_file(a, b, c, box, "magnitude.pvs");
    ASSERT_GT(box.volume(), 0) << s;  // both readers refuse a box whose volume underflows
    const PvsFile f = read_pvs(path);
    const runtime::PvsFile r(path);
    for (int k = 0; k < 300; ++k) {
      const double u = rng.uniform(-1, 1), v = rng.uniform(-1, 1);
      Vec3 p = a + u * (b - a) + v * (c - a);  // on the plane, up to rounding
      for (int ulps = -2; ulps <= 2; ++ulps) {
        Vec3 q = p;
        for (int i = 0; i < std::abs(ulps); ++i) q.z = std::nextafter(q.z, ulps > 0 ? 1e308 : -1e308);
        if (!box.contains(q)) continue;
        ++checked;
        ASSERT_EQ(r.locate(q.x, q.y, q.z), f.locate(q)) << "scale " << s << " point " << q.x << " " << q.y << " " << q.z;
      }
    }
    for (const Vec3& q : {a, b, c, Vec3{0, 0, 0}}) ASSERT_EQ(r.locate(q.x, q.y, q.z), f.locate(q)) << "scale " << s;
  }
  EXPECT_GT(checked, 1000u);
}

/// vc_pvs_open's answer for a file: 0, or the code with the message checked to name the file;
/// vc_pvs_open_compact must give the same.
int open_code(const std::string& path) {
  int codes[2];
  for (int compact : {0, 1}) {
    vc_pvs* p = nullptr;
    char error[256] = "untouched";
    const int code = compact ? vc_pvs_open_compact(path.c_str(), &p, error, sizeof error)
                             : vc_pvs_open(path.c_str(), &p, error, sizeof error);
    if (code == 0) {
      EXPECT_EQ(vc_pvs_is_compact(p), compact);
      vc_pvs_close(p);
    } else {
      EXPECT_EQ(p, nullptr);
      EXPECT_NE(std::string(error).find(path), std::string::npos) << error;
    }
    codes[compact] = code;
  }
  EXPECT_EQ(codes[0], codes[1]) << "the compact handle answers otherwise for " << path;
  const int code = codes[0];
  // The same bytes from memory (vc_pvs_open_memory) get the same answer, the message naming
  // "(memory)".
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (int compact : {0, 1}) {
      vc_pvs* p = nullptr;
      char error[256] = "untouched";
      EXPECT_EQ(vc_pvs_open_memory(bytes.data(), bytes.size(), compact, &p, error, sizeof error), code)
          << "from memory, " << path << ": " << error;
      if (p) {
        EXPECT_EQ(vc_pvs_is_compact(p), compact);
        vc_pvs_close(p);
      } else {
        EXPECT_NE(std::string(error).find("(memory)"), std::string::npos) << error;
      }
    }
  }
  return code;
}

TEST(Runtime, CompactHandleAnswersAsTheExpandedOne) {
  const Level& l = level();
  const runtime::PvsFile full(l.path), compact(l.path, true);
  ASSERT_TRUE(compact.compact());
  ASSERT_FALSE(full.compact());
  ASSERT_EQ(compact.cell_count(), full.cell_count());
  for (uint32_t c = 0; c < full.cell_count(); ++c) {
    const int32_t cell = static_cast<int32_t>(c);
    const std::vector<uint32_t> want = l.file.pvs.cell_pvs(c);
    EXPECT_EQ(compact.objects_copy(cell), want) << "cell " << c;
    EXPECT_EQ(full.objects_copy(cell), want) << "cell " << c;
    EXPECT_EQ(compact.bits(cell), full.bits(cell));
    for (uint32_t o = 0; o < l.file.object_count; ++o) EXPECT_EQ(compact.sees(cell, o), full.sees(cell, o));
    // No expanded list to point at: NULL and 0, never a dangling pointer.
    EXPECT_TRUE(compact.objects(cell).empty());
    EXPECT_EQ(compact.objects(cell).data, nullptr);
  }
  // A short buffer gets the first ids and the full count.
  const std::vector<uint32_t> first = l.file.pvs.cell_pvs(0);
  ASSERT_GE(first.size(), 2u);
  uint32_t two[2] = {0, 0};
  EXPECT_EQ(vc_pvs_cell_objects_copy(compact.handle(), 0, two, 2), first.size());
  EXPECT_EQ(two[0], first[0]);
  EXPECT_EQ(two[1], first[1]);
  EXPECT_EQ(vc_pvs_cell_objects_copy(compact.handle(), -1, two, 2), 0u);
  EXPECT_EQ(vc_pvs_cell_objects_copy(compact.handle(), static_cast<int32_t>(compact.cell_count()), two, 2), 0u);
  Rng rng(4);
  const Box3& box = l.file.bsp.view_box;
  for (int k = 0; k < 2000; ++k) {
    const double x = rng.uniform(box.lo.x, box.hi.x), y = rng.uniform(box.lo.y, box.hi.y),
                 z = rng.uniform(box.lo.z, box.hi.z);
    int32_t cell = -2;
    EXPECT_TRUE(compact.objects_at(x, y, z, &cell).empty());
    EXPECT_EQ(cell, full.locate(x, y, z));
  }
  // The compact handle holds the coded lists and 8 bytes a hierarchy node: list_bytes (the
  // toolkit's measure of a .pvs's lists) plus that index, and less than the expanded sets.
  EXPECT_EQ(compact.list_bytes(), list_bytes(l.file.pvs.stored, l.file.object_count) + 8 * l.file.pvs.node_count());
  EXPECT_LT(compact.list_bytes(), full.list_bytes());
  EXPECT_LT(compact.memory_bytes(), full.memory_bytes());
}

TEST(Runtime, RefusesWhatIsNotAValidPvsFile) {
  const Level& l = level();
  std::ifstream in(l.path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string bad = test::temp_path("bad.pvs");
  EXPECT_NE(open_code(test::temp_path("missing.pvs")), 0);
  std::filesystem::create_directories(test::temp_path("a_directory.pvs"));
  EXPECT_NE(open_code(test::temp_path("a_directory.pvs")), 0);
  for (size_t keep : {size_t{0}, size_t{10}, size_t{32}, bytes.size() / 2, bytes.size() - 1}) {
    test::write_file(bad, bytes.substr(0, keep));
    EXPECT_NE(open_code(bad), 0) << "truncated to " << keep;
  }
  for (size_t at : {size_t{0}, size_t{5}, size_t{40}, bytes.size() / 2, bytes.size() - 1}) {
    std::string flipped = bytes;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x21);
    test::write_file(bad, flipped);
    EXPECT_NE(open_code(bad), 0) << "flipped byte " << at;
  }
  // Well-formed containers whose content is inconsistent: the toolkit refuses them, so must we.
  auto refused = [&](PvsFile f) {
    write_pvs(bad, f);
    EXPECT_THROW(read_pvs(bad), Error);
    return open_code(bad) != 0;
  };
  PvsFile f = l.file;
  f.pvs.parent[0] = 0;
  EXPECT_TRUE(refused(f));
  f = l.file;
  f.pvs.stored.back().push_back(f.object_count + 3);  // not a list the file can hold
  EXPECT_THROW(write_pvs(bad, f), Error);
  f = l.file;
  {  // a cell's path that lists an object twice: a parent keeps what its child keeps too
    size_t c = 0;  // the first node whose parent keeps objects (which one depends on the samples)
    while (c < f.pvs.node_count() && (f.pvs.parent[c] < 0 || f.pvs.stored[f.pvs.parent[c]].empty())) ++c;
    ASSERT_LT(c, f.pvs.node_count());
    const uint32_t o = f.pvs.stored[f.pvs.parent[c]][0];
    auto& mine = f.pvs.stored[c];
    mine.insert(std::upper_bound(mine.begin(), mine.end(), o), o);
    EXPECT_TRUE(refused(f));
  }
  f = l.file;
  *std::find_if(f.leaf_cell.begin(), f.leaf_cell.end(), [](int32_t c) { return c >= 0; }) = 999;
  EXPECT_TRUE(refused(f));
  f = l.file;
  f.bsp.nodes[0].child[1] = f.bsp.nodes[0].child[0];
  EXPECT_TRUE(refused(f));
  f = l.file;
  for (Plane& pl : f.bsp.planes)
    if (!pl.is_axis_aligned()) pl.points[1].y = NAN;
  EXPECT_TRUE(refused(f));
  EXPECT_THROW(runtime::PvsFile{bad}, std::runtime_error);
  EXPECT_NE(vc_pvs_open(nullptr, nullptr, nullptr, 0), 0);
}

/// The payload of the .pvs at `path` with its PVS lists (the last field: a length, then the
/// bytes) replaced by `lists`.
std::string with_lists(const std::string& path, const std::string& lists, uint32_t* version) {
  std::string payload = read_container(path, "VPVS", 2, *version);
  uint64_t n = 0;
  // The lists are the payload's tail: find the length field that spans exactly to the end.
  for (size_t at = payload.size() - 8;; --at) {
    std::memcpy(&n, payload.data() + at, 8);
    if (n == payload.size() - at - 8) {
      payload.resize(at);
      break;
    }
    if (at == 0) ADD_FAILURE() << "no lists found";
  }
  n = lists.size();
  payload.append(reinterpret_cast<const char*>(&n), 8);
  return payload + lists;
}

TEST(Runtime, ReadsVersionOneAndRefusesMalformedLists) {
  const Level& l = level();
  const std::string path = test::temp_path("lists.pvs");
  // Version 1 (files written before the interpolative coding): varints of the differences.
  std::string varints;
  auto put = [&](uint32_t v) {
    for (; v >= 0x80; v >>= 7) varints.push_back(static_cast<char>((v & 0x7f) | 0x80));
    varints.push_back(static_cast<char>(v));
  };
  for (const auto& ids : l.file.pvs.stored) {
    put(static_cast<uint32_t>(ids.size()));
    for (size_t i = 0; i < ids.size(); ++i) put(i ? ids[i] - ids[i - 1] - 1 : ids[i]);
  }
  uint32_t version = 0;
  write_container(path, "VPVS", 1, with_lists(l.path, varints, &version));
  EXPECT_EQ(version, 2u) << "the toolkit writes version 2";
  const PvsFile v1 = read_pvs(path);
  const runtime::PvsFile r1(path), c1(path, true);
  ASSERT_EQ(v1.pvs.cell_count, l.file.pvs.cell_count);
  for (uint32_t c = 0; c < v1.pvs.cell_count; ++c) {
    EXPECT_EQ(v1.pvs.cell_pvs(c), l.file.pvs.cell_pvs(c));
    const runtime::ObjectList got = r1.objects(static_cast<int32_t>(c));
    EXPECT_EQ(std::vector<uint32_t>(got.begin(), got.end()), l.file.pvs.cell_pvs(c));
    EXPECT_EQ(c1.objects_copy(static_cast<int32_t>(c)), l.file.pvs.cell_pvs(c));
  }
  // recode rewrites it in the current format: the same PVSs in fewer bytes.
  const std::string recoded = test::temp_path("recoded.pvs");
  const pipeline::RecodeResult rr = pipeline::recode(path, recoded, 2, [](const std::string&) {});
  EXPECT_EQ(rr.version_before, 1u);
  EXPECT_EQ(rr.list_bytes_before, varints.size());
  EXPECT_LT(rr.list_bytes_after, rr.list_bytes_before);
  uint32_t format = 0;
  const PvsFile v2 = read_pvs(recoded, &format);
  EXPECT_EQ(format, 2u);
  EXPECT_EQ(v2.pvs.stored, l.file.pvs.stored);
  EXPECT_EQ(v2.leaf_cell, l.file.leaf_cell);
  EXPECT_EQ(v2.object_names, l.file.object_names);
  // Version 2 lists cut short, with a byte or a padding bit too many, or a size beyond the
  // objects: both readers refuse them.
  const std::string good = id_lists::encode(l.file.pvs.stored, l.file.object_count);
  ASSERT_GT(good.size(), 4u);
  std::vector<uint32_t> too_many(l.file.object_count + 1);
  for (uint32_t i = 0; i < too_many.size(); ++i) too_many[i] = i;
  std::vector<std::vector<uint32_t>> oversized = l.file.pvs.stored;
  oversized[0] = too_many;
  std::string padded = good;
  padded.back() = static_cast<char>(padded.back() | 0x80);
  const bool last_bit_used = good.back() & 0x80;
  for (const std::string& lists :
       {good.substr(0, good.size() - 1), good + std::string(1, '\0'), padded, id_lists::encode(oversized, l.file.object_count + 1),
        std::string(good.size(), '\0')}) {
    if (lists == padded && last_bit_used) continue;  // no padding bit to set
    write_container(path, "VPVS", 2, with_lists(l.path, lists, &version));
    EXPECT_THROW(read_pvs(path), Error);
    EXPECT_NE(open_code(path), 0);
  }
  write_container(path, "VPVS", 2, with_lists(l.path, good, &version));
  EXPECT_NO_THROW(read_pvs(path));
  EXPECT_EQ(open_code(path), 0);
}

/// The payload of the .pvs at `path` with the view box's coordinates of `axis` set to [lo, hi]
/// (the payload: fingerprint, object count, names, rule, then lo[3] and hi[3]), in a valid
/// container: what a file written elsewhere, or damaged before its checksum was taken, holds.
std::string with_view_box(const std::string& path, int axis, double lo, double hi, const std::string& name) {
  uint32_t version = 0;
  std::string payload = read_container(path, "VPVS", 2, version);
  size_t at = 12;
  auto skip_string = [&] {
    uint64_t n = 0;
    std::memcpy(&n, payload.data() + at, 8);
    at += 8 + n;
  };
  uint64_t names = 0;
  std::memcpy(&names, payload.data() + at, 8);
  at += 8;
  for (uint64_t i = 0; i < names; ++i) skip_string();
  skip_string();  // the rule
  std::memcpy(payload.data() + at + 8 * axis, &lo, 8);
  std::memcpy(payload.data() + at + 24 + 8 * axis, &hi, 8);
  const std::string out = test::temp_path(name);
  write_container(out, "VPVS", version, payload);
  return out;
}

TEST(Runtime, LocatesLikeTheToolkitInExtremeViewBoxes) {
  // Boxes a valid container can carry: a span of 1e-310 (its grid scale overflows), of 2e308
  // (hi - lo overflows), far from the origin, of 5.4e307 (the fuzzer's box: extent x grid index
  // overflowed; data/fuzz/regressions/pvs/runtime-disagrees-grid-overflow, whose root plane is
  // axial, reproduces that, these planes do not). The runtime once indexed its grid with
  // static_cast<int>(inf or NaN) here and crashed while `viewcells query` answered.
  const Level& l = level();
  const Box3& box = l.file.bsp.view_box;
  const double huge = std::numeric_limits<double>::max();
  struct Case {
    int axis;
    double lo, hi;
  };
  size_t opened = 0, located = 0;
  for (const Case& c : {Case{0, 0, 1e-310}, Case{0, -1e308, 1e308}, Case{1, -huge, huge}, Case{2, 1e300, 1.5e300},
                        Case{0, -5e-324, 5e-324}, Case{2, box.lo.z, 1e308}, Case{1, -1e308, box.hi.y},
                        Case{0, -5.3751024732383243e+307, 59205627325.29705}}) {
    SCOPED_TRACE("axis " + std::to_string(c.axis) + " [" + std::to_string(c.lo) + ", " + std::to_string(c.hi) + "]");
    const std::string path = with_view_box(l.path, c.axis, c.lo, c.hi, "extreme_box.pvs");
    PvsFile f;
    try {
      f = read_pvs(path);
    } catch (const Error&) {
      EXPECT_NE(open_code(path), 0) << "the toolkit refuses it, so must the runtime";
      continue;
    }
    ASSERT_EQ(open_code(path), 0) << "the toolkit reads it, so must the runtime";
    ++opened;
    const runtime::PvsFile r(path), compact(path, true);
    const Box3& b = f.bsp.view_box;
    std::vector<Vec3> points = {b.lo, b.hi, b.center(), box.center(), box.lo, box.hi, Vec3{0, 0, 0}};
    Rng rng(3);
    for (int k = 0; k < 500; ++k) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) {
        const double u = rng.uniform();
        // Half uniform in the box (which may overflow to inf: then its ends), half in the level's box.
        const double t = k % 2 ? b.lo[a] + u * (b.hi[a] - b.lo[a]) : box.lo[a] + u * (box.hi[a] - box.lo[a]);
        p[a] = std::isfinite(t) ? t : (u < 0.5 ? b.lo[a] : b.hi[a]);
      }
      points.push_back(p);
    }
    const double odd[] = {NAN, INFINITY, -INFINITY, huge, -huge, 5e-324, -0.0};
    for (double v : odd) points.push_back(Vec3{v, box.center().y, box.center().z});
    for (const Vec3& p : points) {
      const int32_t want = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) ? f.locate(p) : -1;
      ASSERT_EQ(r.locate(p.x, p.y, p.z), want) << p.x << " " << p.y << " " << p.z;
      ASSERT_EQ(compact.locate(p.x, p.y, p.z), want);
      int32_t at = -2;
      const runtime::ObjectList seen = r.objects_at(p.x, p.y, p.z, &at);
      ASSERT_EQ(at, want);
      if (want >= 0) {
        ++located;
        ASSERT_EQ(std::vector<uint32_t>(seen.begin(), seen.end()), f.pvs.cell_pvs(static_cast<uint32_t>(want)));
        ASSERT_EQ(compact.objects_copy(want), f.pvs.cell_pvs(static_cast<uint32_t>(want)));
      }
    }
  }
  EXPECT_GE(opened, 5u);
  EXPECT_GT(located, 1000u);
}

TEST(Runtime, EveryFunctionTakesANullHandle) {
  const vc_pvs* none = nullptr;
  EXPECT_EQ(vc_pvs_cell_count(none), 0u);
  EXPECT_EQ(vc_pvs_object_count(none), 0u);
  EXPECT_EQ(vc_pvs_row_bytes(none), 0u);
  EXPECT_EQ(vc_pvs_scene_fingerprint(none), 0u);
  EXPECT_STREQ(vc_pvs_rule(none), "");
  EXPECT_STREQ(vc_pvs_object_name(none, 0), "");
  EXPECT_EQ(vc_pvs_memory_bytes(none), 0u);
  EXPECT_EQ(vc_pvs_list_bytes(none), 0u);
  EXPECT_EQ(vc_pvs_is_compact(none), 0);
  double lo[3] = {1, 1, 1}, hi[3] = {1, 1, 1};
  vc_pvs_view_box(none, lo, hi);
  EXPECT_TRUE(std::isnan(lo[0]) && std::isnan(hi[2]));
  vc_pvs_view_box(none, nullptr, nullptr);
  EXPECT_EQ(vc_pvs_locate(none, 0, 0, 0), -1);
  const uint32_t* ids = reinterpret_cast<const uint32_t*>(&lo);
  size_t count = 7;
  EXPECT_EQ(vc_pvs_locate_objects(none, 0, 0, 0, &ids, &count), -1);
  EXPECT_EQ(ids, nullptr);
  EXPECT_EQ(count, 0u);
  EXPECT_EQ(vc_pvs_locate_objects(none, 0, 0, 0, nullptr, nullptr), -1);
  EXPECT_EQ(vc_pvs_cell_objects(none, 0, &ids), 0u);
  uint32_t buffer[4];
  EXPECT_EQ(vc_pvs_cell_objects_copy(none, 0, buffer, 4), 0u);
  uint8_t row[4];
  EXPECT_EQ(vc_pvs_cell_bits(none, 0, row, sizeof row), -1);
  EXPECT_EQ(vc_pvs_cell_sees(none, 0, 0), 0);
  vc_pvs_close(nullptr);
  // And NULL outputs on a real handle.
  const runtime::PvsFile r(level().path);
  vc_pvs_view_box(r.handle(), nullptr, hi);
  EXPECT_EQ(hi[0], level().file.bsp.view_box.hi.x);
  EXPECT_GT(vc_pvs_cell_objects_copy(r.handle(), 0, nullptr, 100), 0u);
  EXPECT_EQ(vc_pvs_cell_bits(r.handle(), 0, nullptr, 100), -1);
}

}  // namespace
}  // namespace viewcells
