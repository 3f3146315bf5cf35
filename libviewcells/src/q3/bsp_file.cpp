// Quake 3 BSP reader. Layout (little-endian): "IBSP", version, then 17 lumps (18 for version
// 47) of {offset, length}; the lumps used here are entities 0, shaders 1, planes 2, nodes 3,
// leafs 4, leafsurfaces 5, models 7, drawverts 10, drawindexes 11, surfaces 13, visibility 16.
#include "viewcells/q3/bsp_file.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"

namespace viewcells {

namespace {

constexpr const char* kLumpNames[] = {"entities", "shaders", "planes", "nodes", "leafs", "leafsurfaces",
                                      "leafbrushes", "models", "brushes", "brushsides", "drawverts",
                                      "drawindexes", "fogs", "surfaces", "lightmaps", "lightgrid", "visibility"};

class Reader {
 public:
  Reader(const std::string& bytes, const std::string& name) : b_(bytes), name_(name) {}

  [[noreturn]] void fail(const std::string& what) const { throw Error(name_, 0, "Quake 3 BSP: " + what); }

  int32_t i32(size_t at) const {
    if (at + 4 > b_.size()) fail("file ends early");
    int32_t v;
    std::memcpy(&v, b_.data() + at, 4);
    return v;
  }
  float f32(size_t at) const {
    if (at + 4 > b_.size()) fail("file ends early");
    float v;
    std::memcpy(&v, b_.data() + at, 4);
    if (!std::isfinite(v)) fail("non-finite number at byte " + std::to_string(at));
    return v;
  }

  /// Lump `l`: its offset and number of records of `size` bytes, bounds-checked.
  std::pair<size_t, size_t> lump(int l, size_t size) const {
    const int32_t off = i32(8 + 8 * l), len = i32(12 + 8 * l);
    if (off < 0 || len < 0 || static_cast<size_t>(off) + static_cast<size_t>(len) > b_.size())
      fail(std::string("lump '") + kLumpNames[l] + "' lies outside the file (truncated?)");
    if (len % size != 0)
      fail(std::string("lump '") + kLumpNames[l] + "' is not a whole number of " + std::to_string(size) + "-byte records");
    return {static_cast<size_t>(off), static_cast<size_t>(len) / size};
  }
  std::string str(size_t at, size_t n) const { return b_.substr(at, n); }

 private:
  const std::string& b_;
  std::string name_;
};

Vec3 bezier(const Vec3 c[9], double u, double v) {
  auto b = [](double t, int i) { return i == 0 ? (1 - t) * (1 - t) : (i == 1 ? 2 * t * (1 - t) : t * t); };
  Vec3 p{0, 0, 0};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) p = p + c[3 * j + i] * (b(u, i) * b(v, j));
  return p;
}

}  // namespace

bool Q3Map::cluster_sees(int32_t a, int32_t b) const {
  if (a < 0 || b < 0 || a >= cluster_count || b >= cluster_count) return false;
  return visibility[static_cast<size_t>(a) * cluster_bytes + (b >> 3)] & (1 << (b & 7));
}

Q3SurfaceKind Q3Map::kind(const Q3Surface& s) const {
  const Q3Shader& sh = shaders[s.shader];
  if (s.type == Q3SurfaceType::kFlare || s.type == Q3SurfaceType::kBad) return Q3SurfaceKind::kSkipped;
  if (sh.surface_flags & (kQ3SurfNodraw | kQ3SurfHint | kQ3SurfSkip)) return Q3SurfaceKind::kSkipped;
  if (sh.surface_flags & kQ3SurfSky) return Q3SurfaceKind::kSky;
  if (sh.content_flags &
      (kQ3ContentsWater | kQ3ContentsFog | kQ3ContentsSlime | kQ3ContentsLava | kQ3ContentsTranslucent))
    return Q3SurfaceKind::kNonOccluding;
  return Q3SurfaceKind::kOpaque;
}

int32_t Q3Map::leaf_at(const Vec3& p) const {
  int32_t n = 0;
  for (size_t steps = 0; n >= 0; ++steps) {
    if (steps > nodes.size()) throw Error(path, 0, "Quake 3 BSP: the node tree has a cycle");
    const Q3Node& node = nodes[n];
    const Q3Plane& pl = planes[node.plane];
    n = node.children[dot(pl.normal, p) - pl.dist >= 0 ? 0 : 1];
  }
  return -(n + 1);
}

void Q3Map::column_leaves(const Vec3& base, std::span<const double> heights, std::vector<int32_t>& out) const {
  // At a node, the side test of the column's points is monotone along the column: only z
  // varies, and rounding keeps n.z * z, and a sum with the same other terms, monotone. So the
  // points on either side form a run, found by bisection with leaf_at's own test.
  struct Run {
    int32_t node;
    uint32_t lo, hi;  ///< the points [lo, hi) that reach the node
    size_t depth;
  };
  if (!std::is_sorted(heights.begin(), heights.end()))
    throw Error(path, 0, "the heights of a column's points must ascend");
  out.assign(heights.size(), -1);
  if (heights.empty()) return;
  const Vec3 up{0, 0, 1};
  // Pending runs hold disjoint points: at most one per point.
  std::array<Run, 64> small;
  std::vector<Run> large(heights.size() > small.size() ? heights.size() : 0);
  Run* const stack = large.empty() ? small.data() : large.data();
  size_t pending = 0;
  stack[pending++] = Run{0, 0, static_cast<uint32_t>(heights.size()), 0};
  while (pending > 0) {
    const Run run = stack[--pending];
    if (run.node < 0) {
      std::fill(out.begin() + run.lo, out.begin() + run.hi, -(run.node + 1));
      continue;
    }
    if (run.depth > nodes.size()) throw Error(path, 0, "Quake 3 BSP: the node tree has a cycle");
    const Q3Node& node = nodes[run.node];
    const Q3Plane& pl = planes[node.plane];
    const auto front = [&](uint32_t k) { return dot(pl.normal, base + up * heights[k]) - pl.dist >= 0; };
    const bool first = front(run.lo), last = front(run.hi - 1);
    if (first == last) {
      stack[pending++] = Run{node.children[first ? 0 : 1], run.lo, run.hi, run.depth + 1};
      continue;
    }
    // b: the first point on the last point's side; [lo, b) are on the first point's side.
    uint32_t a = run.lo, b = run.hi - 1;
    while (b - a > 1) {
      const uint32_t mid = a + (b - a) / 2;
      (front(mid) == first ? a : b) = mid;
    }
    stack[pending++] = Run{node.children[first ? 0 : 1], run.lo, b, run.depth + 1};
    stack[pending++] = Run{node.children[last ? 0 : 1], b, run.hi, run.depth + 1};
  }
}

bool Q3Map::in_brush(const Q3Brush& b, const Vec3& p, double slack) const {
  for (int32_t k = 0; k < b.side_count; ++k) {
    const Q3Plane& pl = planes[brush_sides[b.first_side + k].plane];
    if (dot(pl.normal, p) - pl.dist > slack) return false;
  }
  return true;
}

bool Q3Map::opaque_brush(const Q3Brush& b) const {
  const int32_t contents = shaders[b.shader].content_flags;
  return (contents & kQ3ContentsSolid) && !(contents & kQ3ContentsTranslucent);
}

namespace {

/// Whether i indexes one of n items.
bool is_index(int32_t i, size_t n) { return i >= 0 && static_cast<size_t>(i) < n; }
/// Whether the items [first, first + count) all exist among n.
bool in_range(int32_t first, int32_t count, size_t n) {
  return first >= 0 && count >= 0 && static_cast<size_t>(first) + static_cast<size_t>(count) <= n;
}

}  // namespace

namespace {

/// Entities, shaders, planes, leaves and the BSP nodes.
void read_tree(Reader& r, Q3Map& m) {
  auto [eo, elen] = r.lump(0, 1);
  m.entities = r.str(eo, elen);
  while (!m.entities.empty() && m.entities.back() == '\0') m.entities.pop_back();

  auto [so, sn] = r.lump(1, 72);
  for (size_t i = 0; i < sn; ++i) {
    Q3Shader s;
    const std::string raw = r.str(so + 72 * i, 64);
    s.name = raw.substr(0, raw.find('\0'));
    s.surface_flags = r.i32(so + 72 * i + 64);
    s.content_flags = r.i32(so + 72 * i + 68);
    m.shaders.push_back(std::move(s));
  }
  auto [po, pn] = r.lump(2, 16);
  for (size_t i = 0; i < pn; ++i)
    m.planes.push_back({{r.f32(po + 16 * i), r.f32(po + 16 * i + 4), r.f32(po + 16 * i + 8)}, r.f32(po + 16 * i + 12)});
  auto [lo, ln] = r.lump(4, 48);
  for (size_t i = 0; i < ln; ++i) {
    const size_t at = lo + 48 * i;
    Q3Leaf l;
    l.cluster = r.i32(at);
    l.area = r.i32(at + 4);
    l.bounds = {{double(r.i32(at + 8)), double(r.i32(at + 12)), double(r.i32(at + 16))},
                {double(r.i32(at + 20)), double(r.i32(at + 24)), double(r.i32(at + 28))}};
    l.first_surface = r.i32(at + 32);
    l.surface_count = r.i32(at + 36);
    l.first_brush = r.i32(at + 40);
    l.brush_count = r.i32(at + 44);
    m.leaves.push_back(l);
  }
  auto [no, nn] = r.lump(3, 36);
  for (size_t i = 0; i < nn; ++i) {
    const size_t at = no + 36 * i;
    Q3Node n;
    n.plane = r.i32(at);
    n.children[0] = r.i32(at + 4);
    n.children[1] = r.i32(at + 8);
    if (!is_index(n.plane, m.planes.size())) r.fail("node " + std::to_string(i) + " names a missing plane");
    for (int32_t c : n.children)
      if ((c >= 0 && (static_cast<size_t>(c) >= nn || static_cast<size_t>(c) <= i)) ||
          (c < 0 && static_cast<size_t>(-(c + 1)) >= m.leaves.size()))
        r.fail("node " + std::to_string(i) + " has a child that does not exist");
    m.nodes.push_back(n);
  }
  if (m.nodes.empty()) r.fail("the map has no BSP nodes");
}

/// Drawn surfaces, their vertices and indices, the world model, and the leaves' surfaces.
void read_surfaces(Reader& r, Q3Map& m) {
  auto [lso, lsn] = r.lump(5, 4);
  for (size_t i = 0; i < lsn; ++i) m.leaf_surfaces.push_back(r.i32(lso + 4 * i));
  auto [vo, vn] = r.lump(10, 44);
  for (size_t i = 0; i < vn; ++i) m.vertices.push_back({r.f32(vo + 44 * i), r.f32(vo + 44 * i + 4), r.f32(vo + 44 * i + 8)});
  auto [io, in] = r.lump(11, 4);
  for (size_t i = 0; i < in; ++i) m.indices.push_back(r.i32(io + 4 * i));
  auto [fo, fn] = r.lump(13, 104);
  for (size_t i = 0; i < fn; ++i) {
    const size_t at = fo + 104 * i;
    Q3Surface s;
    s.shader = r.i32(at);
    s.type = static_cast<Q3SurfaceType>(r.i32(at + 8));
    s.first_vertex = r.i32(at + 12);
    s.vertex_count = r.i32(at + 16);
    s.first_index = r.i32(at + 20);
    s.index_count = r.i32(at + 24);
    s.patch_width = r.i32(at + 96);
    s.patch_height = r.i32(at + 100);
    const std::string which = "surface " + std::to_string(i);
    if (!is_index(s.shader, m.shaders.size())) r.fail(which + " names a missing shader");
    if (!in_range(s.first_vertex, s.vertex_count, vn))
      r.fail(which + " has vertices outside the drawverts lump");
    if (!in_range(s.first_index, s.index_count, in))
      r.fail(which + " has indices outside the drawindexes lump");
    if (s.type == Q3SurfaceType::kPlanar || s.type == Q3SurfaceType::kTriangleSoup) {
      if (s.index_count % 3 != 0) r.fail(which + " has a partial triangle");
      for (int32_t k = 0; k < s.index_count; ++k) {
        const int32_t v = m.indices[s.first_index + k];
        if (v < 0 || v >= s.vertex_count) r.fail(which + " indexes a vertex it does not own");
      }
    }
    if (s.type == Q3SurfaceType::kPatch &&
        (s.patch_width < 3 || s.patch_height < 3 || s.patch_width % 2 == 0 || s.patch_height % 2 == 0 ||
         static_cast<int64_t>(s.patch_width) * s.patch_height != s.vertex_count))
      r.fail(which + " is a patch with a malformed control grid");
    m.surfaces.push_back(s);
  }
  auto [mo, mn] = r.lump(7, 40);
  if (mn == 0) r.fail("the map has no world model");
  m.world_first_surface = r.i32(mo + 24);
  m.world_surface_count = r.i32(mo + 28);
  m.world_first_brush = r.i32(mo + 32);
  m.world_brush_count = r.i32(mo + 36);
  if (!in_range(m.world_first_surface, m.world_surface_count, fn))
    r.fail("the world model's surfaces lie outside the surfaces lump");
  for (const Q3Leaf& l : m.leaves)
    if (!in_range(l.first_surface, l.surface_count, lsn))
      r.fail("a leaf's surfaces lie outside the leafsurfaces lump");
  for (int32_t s : m.leaf_surfaces)
    if (!is_index(s, fn)) r.fail("a leaf names a missing surface");

}

/// Brushes: what made a leaf solid (for explaining rays that cross solid space).
void read_brushes(Reader& r, Q3Map& m) {
  auto [bso, bsn] = r.lump(9, 8);
  for (size_t i = 0; i < bsn; ++i) {
    Q3BrushSide side{r.i32(bso + 8 * i), r.i32(bso + 8 * i + 4)};
    if (!is_index(side.plane, m.planes.size()) || !is_index(side.shader, m.shaders.size()))
      r.fail("brush side " + std::to_string(i) + " names a missing plane or shader");
    m.brush_sides.push_back(side);
  }
  auto [bo, bn] = r.lump(8, 12);
  for (size_t i = 0; i < bn; ++i) {
    Q3Brush b{r.i32(bo + 12 * i), r.i32(bo + 12 * i + 4), r.i32(bo + 12 * i + 8)};
    if (!in_range(b.first_side, b.side_count, bsn) || !is_index(b.shader, m.shaders.size()))
      r.fail("brush " + std::to_string(i) + " has sides outside the brushsides lump or a missing shader");
    m.brushes.push_back(b);
  }
  auto [lbo, lbn] = r.lump(6, 4);
  for (size_t i = 0; i < lbn; ++i) {
    m.leaf_brushes.push_back(r.i32(lbo + 4 * i));
    if (!is_index(m.leaf_brushes.back(), bn)) r.fail("a leaf names a missing brush");
  }
  if (!in_range(m.world_first_brush, m.world_brush_count, bn))
    r.fail("the world model's brushes lie outside the brushes lump");
  for (const Q3Leaf& l : m.leaves)
    if (!in_range(l.first_brush, l.brush_count, lbn))
      r.fail("a leaf's brushes lie outside the leafbrushes lump");

}

/// q3map2's cluster rows (the map's PVS), when the map was vis-compiled.
void read_visibility(Reader& r, Q3Map& m) {
  auto [viso, vislen] = r.lump(16, 1);
  if (vislen > 0) {
    if (vislen < 8) r.fail("the visibility lump ends early");
    m.cluster_count = r.i32(viso);
    m.cluster_bytes = r.i32(viso + 4);
    if (m.cluster_count < 0 || m.cluster_bytes < 0 || m.cluster_bytes < (m.cluster_count + 7) / 8 ||
        8 + static_cast<int64_t>(m.cluster_count) * m.cluster_bytes > static_cast<int64_t>(vislen))
      r.fail("the visibility lump does not hold its " + std::to_string(m.cluster_count) + " cluster rows");
    const std::string rows = r.str(viso + 8, static_cast<size_t>(m.cluster_count) * m.cluster_bytes);
    m.visibility.assign(rows.begin(), rows.end());
    for (const Q3Leaf& l : m.leaves)
      if (l.cluster >= m.cluster_count) r.fail("a leaf names cluster " + std::to_string(l.cluster) + " of " + std::to_string(m.cluster_count));
  }
}

}  // namespace

Q3Map parse_q3bsp(const std::string& bytes, const std::string& name) {
  Reader r(bytes, name);
  if (bytes.size() < 8 || bytes.compare(0, 4, "IBSP") != 0) r.fail("not a Quake 3 BSP file (no IBSP header)");
  Q3Map m;
  m.path = name;
  m.version = r.i32(4);
  if (m.version != 46 && m.version != 47)
    r.fail("version " + std::to_string(m.version) + " is not supported (46 and 47 are)");
  if (bytes.size() < 8 + 8 * 17) r.fail("header ends early");

  read_tree(r, m);
  read_surfaces(r, m);
  read_brushes(r, m);
  read_visibility(r, m);
  return m;
}

Q3Map read_q3bsp(const std::string& path) {
  return parse_q3bsp(read_file_bytes(path), path);
}

namespace {

/// The faces of brush `b` with its sides moved `inset` inwards, as triangles appended to
/// `mesh` in `group` (outward facing): each side's plane cut to a polygon by all the others.
/// Returns false when nothing is left (a brush thinner than twice the inset).
bool add_brush_hull(const Q3Map& map, const Q3Brush& b, double inset, uint32_t group, RawMesh& mesh) {
  constexpr double kHuge = 1 << 17;  // beyond any Quake 3 coordinate
  bool any = false;
  std::vector<Vec3> poly, next;
  for (int32_t i = 0; i < b.side_count; ++i) {
    const Q3Plane& pi = map.planes[map.brush_sides[b.first_side + i].plane];
    const Vec3 n = normalize(pi.normal);
    const double d = pi.dist / length(pi.normal) - inset;
    // A huge square on the plane, counter-clockwise seen from its front (outside the brush).
    Vec3 u, v;
    orthonormal_basis(n, u, v);
    const Vec3 c = n * d;
    poly = {c - u * kHuge - v * kHuge, c + u * kHuge - v * kHuge, c + u * kHuge + v * kHuge, c - u * kHuge + v * kHuge};
    for (int32_t j = 0; j < b.side_count && !poly.empty(); ++j) {
      if (j == i) continue;
      const Q3Plane& pj = map.planes[map.brush_sides[b.first_side + j].plane];
      const Vec3 nj = normalize(pj.normal);
      const double dj = pj.dist / length(pj.normal) - inset;
      next.clear();  // keep the part behind side j (Sutherland-Hodgman)
      for (size_t k = 0; k < poly.size(); ++k) {
        const Vec3& p = poly[k];
        const Vec3& q = poly[(k + 1) % poly.size()];
        const double dp = dot(nj, p) - dj, dq = dot(nj, q) - dj;
        if (dp <= 0) next.push_back(p);
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) next.push_back(p + (q - p) * (dp / (dp - dq)));
      }
      poly.swap(next);
    }
    if (poly.size() < 3) continue;
    any = true;
    const uint32_t first = static_cast<uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), poly.begin(), poly.end());
    for (uint32_t k = 1; k + 1 < poly.size(); ++k) {
      mesh.triangles.push_back({first, first + k, first + k + 1});
      mesh.triangle_group.push_back(group);
    }
  }
  return any;
}

}  // namespace

RawMesh q3_world_mesh(const Q3Map& map, const Q3MeshOptions& options, Q3MeshStats* stats) {
  const int patch_level = options.patch_level;
  const bool with_sky = options.sky;
  if (patch_level < 1 || patch_level > 64) throw Error("patch tessellation level must be between 1 and 64");
  if (!(options.hull_inset >= 0) || !std::isfinite(options.hull_inset)) throw Error("the brush hull inset must be >= 0");
  RawMesh mesh;
  Q3MeshStats local;
  Q3MeshStats& st = stats ? *stats : local;
  st = Q3MeshStats{};
  for (int32_t si = map.world_first_surface; si < map.world_first_surface + map.world_surface_count; ++si) {
    const Q3Surface& s = map.surfaces[si];
    const Q3SurfaceKind kind = map.kind(s);
    ++st.surfaces[static_cast<int>(kind)];
    if (kind == Q3SurfaceKind::kSkipped) continue;
    if (kind == Q3SurfaceKind::kSky && !with_sky) continue;
    if (kind == Q3SurfaceKind::kNonOccluding && !options.see_through) continue;
    const uint32_t group = static_cast<uint32_t>(mesh.group_names.size());
    mesh.group_names.push_back(map.shaders[s.shader].name + "#" + std::to_string(si));
    mesh.group_rendered.push_back(kind != Q3SurfaceKind::kSky);  // the sky closes the map but is not drawn as one
    mesh.group_occluder.push_back(kind != Q3SurfaceKind::kNonOccluding);
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
      mesh.triangles.push_back({a, b, c});
      mesh.triangle_group.push_back(group);
    };
    const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
    if (s.type == Q3SurfaceType::kPatch) {
      ++st.patches;
      const int w = s.patch_width, h = s.patch_height, n = patch_level;
      for (int py = 0; py + 2 < h; py += 2)
        for (int px = 0; px + 2 < w; px += 2) {
          Vec3 c[9];
          for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) c[3 * j + i] = map.vertices[s.first_vertex + (py + j) * w + px + i];
          const uint32_t first = static_cast<uint32_t>(mesh.vertices.size());
          for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) mesh.vertices.push_back(bezier(c, double(i) / n, double(j) / n));
          for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
              const uint32_t a = first + j * (n + 1) + i, b = a + 1, d = a + (n + 1), e = d + 1;
              // The front of a patch is along du x dv (checked against the maps' vertex normals).
              add(a, b, d);
              add(b, e, d);
            }
        }
      continue;
    }
    for (int32_t k = 0; k < s.vertex_count; ++k) mesh.vertices.push_back(map.vertices[s.first_vertex + k]);
    for (int32_t k = 0; k + 2 < s.index_count; k += 3) {
      const int32_t* idx = &map.indices[s.first_index + k];
      // Quake 3 winds triangles clockwise seen from the front (checked against the maps'
      // vertex normals); the scene wants counter-clockwise.
      add(base + idx[0], base + idx[2], base + idx[1]);
    }
  }
  if (options.brush_hulls) {
    const uint32_t group = static_cast<uint32_t>(mesh.group_names.size());
    mesh.group_names.push_back("solid brushes");
    mesh.group_rendered.push_back(false);
    mesh.group_occluder.push_back(true);
    for (int32_t bi = map.world_first_brush; bi < map.world_first_brush + map.world_brush_count; ++bi) {
      const Q3Brush& b = map.brushes[bi];
      if (!map.opaque_brush(b)) continue;
      st.brush_hulls += add_brush_hull(map, b, options.hull_inset, group, mesh);
    }
  }
  st.spawn_points = q3_spawn_points(map).size();
  return mesh;
}

double q3_far_plane(const Q3Map& map) {
  // The worldspawn is the first entity.
  const size_t end = map.entities.find('}');
  const std::string world = map.entities.substr(0, end);
  const std::string key = "\"_farplanedist\"";
  const size_t k = world.find(key);
  if (k == std::string::npos) return 0;
  const size_t a = world.find('"', k + key.size()), b = a == std::string::npos ? a : world.find('"', a + 1);
  if (b == std::string::npos) return 0;
  try {
    const double d = std::stod(world.substr(a + 1, b - a - 1));
    return std::isfinite(d) && d > 0 ? d : 0;
  } catch (const std::exception&) {
    return 0;
  }
}

std::vector<Vec3> q3_spawn_points(const Q3Map& map) {
  std::vector<Vec3> out;
  std::string classname, origin;
  std::istringstream in(map.entities);
  std::string line;
  auto flush = [&] {
    const bool spawn = classname == "info_player_deathmatch" || classname == "info_player_start" ||
                       classname == "team_CTF_redplayer" || classname == "team_CTF_blueplayer" ||
                       classname == "team_CTF_redspawn" || classname == "team_CTF_bluespawn";
    if (spawn && !origin.empty()) {
      Vec3 p;
      std::istringstream o(origin);
      if (o >> p.x >> p.y >> p.z) out.push_back(p);
    }
    classname.clear();
    origin.clear();
  };
  while (std::getline(in, line)) {
    const size_t a = line.find('"');
    if (line.find('}') != std::string::npos && a == std::string::npos) {
      flush();
      continue;
    }
    if (a == std::string::npos) continue;
    const size_t b = line.find('"', a + 1), c = line.find('"', b + 1), d = line.find('"', c + 1);
    if (b == std::string::npos || c == std::string::npos || d == std::string::npos) continue;
    const std::string key = line.substr(a + 1, b - a - 1), value = line.substr(c + 1, d - c - 1);
    if (key == "classname") classname = value;
    if (key == "origin") origin = value;
  }
  flush();
  return out;
}


}  // namespace viewcells
