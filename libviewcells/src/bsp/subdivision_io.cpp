#include "viewcells/bsp/subdivision_io.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "viewcells/core/error.h"
#include "viewcells/io/binary_file.h"

namespace viewcells {

void put_planes(ByteWriter& w, const std::vector<Plane>& planes) {
  w.put<uint64_t>(planes.size());
  for (const Plane& p : planes) {
    w.put<int32_t>(p.axis);
    w.put(p.normal);
    w.put(p.offset);
    for (const Vec3& q : p.points) w.put(q);
  }
}

std::vector<Plane> get_planes(ByteReader& r, uint64_t max_items) {
  const uint64_t count = r.get<uint64_t>();
  if (count < 6 || count > max_items) r.fail("invalid plane count");
  std::vector<Plane> planes(count);
  for (Plane& p : planes) {
    p.axis = r.get<int32_t>();
    p.normal = r.get<Vec3>();
    p.offset = r.get<double>();
    for (Vec3& q : p.points) q = r.get<Vec3>();
    if (p.axis < -1 || p.axis > 2 || !is_finite(p.normal) || !std::isfinite(p.offset)) r.fail("invalid plane");
    // A geometry-aligned plane's side is decided exactly from its points: they must be numbers.
    if (p.axis < 0 && !(is_finite(p.points[0]) && is_finite(p.points[1]) && is_finite(p.points[2])))
      r.fail("invalid plane");
  }
  return planes;
}

Box3 get_view_box(ByteReader& r) {
  Box3 b;
  b.lo = r.get<Vec3>();
  b.hi = r.get<Vec3>();
  if (!(b.volume() > 0) || !is_finite(b.lo) || !is_finite(b.hi)) r.fail("invalid view box");
  return b;
}

std::vector<std::vector<uint32_t>> leaf_pvs(const Subdivision& s, const SegmentSet& segments) {
  std::vector<std::vector<uint32_t>> pvs(s.nodes.size());
  for (int32_t leaf : s.leaves()) {
    auto& ids = pvs[leaf];
    for (uint32_t i : s.segments[leaf])
      for (uint32_t o : {segments.object_a[i], segments.object_b[i]})
        if (o != kNoObject) ids.push_back(o);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  }
  return pvs;
}

namespace {
constexpr char kMagic[5] = "VCEL";
// 1: first layout; 2: adds the pixel term's screen (width, height, field of view) after c;
// 3: adds the merge history and the object names at the end.
constexpr uint32_t kVersion = 3;

void put_history(ByteWriter& w, const std::optional<MergeHistory>& h) {
  w.put<uint8_t>(h ? 1 : 0);
  if (!h) return;
  w.put<uint32_t>(h->leaf_count);
  w.put<uint64_t>(h->nodes.size());
  for (const MergeNode& n : h->nodes) {
    w.put<int32_t>(n.child[0]);
    w.put<int32_t>(n.child[1]);
    w.put<int32_t>(n.parent);
    w.put(n.weight);
    w.put(n.volume);
    w.put(n.bounds.lo);
    w.put(n.bounds.hi);
    w.put(n.pvs_cost);
    w.put<uint32_t>(n.pvs_size);
  }
  w.put(h->initial_cost);
  w.put(h->total_weight);
  for (double c : h->cost_after) w.put(c);
}

/// Reads and checks the merge history against the subdivision's leaves and their PVSs.
std::optional<MergeHistory> get_history(ByteReader& r, const Subdivision& s,
                                        const std::vector<std::vector<uint32_t>>& leaf_pvs, uint64_t max_items) {
  if (r.get<uint8_t>() == 0) return std::nullopt;
  MergeHistory h;
  h.leaf_count = r.get<uint32_t>();
  const std::vector<int32_t> leaves = s.leaves();
  if (h.leaf_count != leaves.size()) r.fail("the merge history does not match the subdivision's leaves");
  const uint64_t nodes = r.get<uint64_t>();
  if (nodes < h.leaf_count || nodes > 2ull * h.leaf_count - 1 || nodes > max_items) r.fail("invalid merge node count");
  h.nodes.resize(nodes);
  for (MergeNode& n : h.nodes) {
    n.child[0] = r.get<int32_t>();
    n.child[1] = r.get<int32_t>();
    n.parent = r.get<int32_t>();
    n.weight = r.get<double>();
    n.volume = r.get<double>();
    n.bounds.lo = r.get<Vec3>();
    n.bounds.hi = r.get<Vec3>();
    n.pvs_cost = r.get<double>();
    n.pvs_size = r.get<uint32_t>();
    if (!(n.weight >= 0) || !(n.volume > 0) || !(n.pvs_cost >= 0) || !std::isfinite(n.pvs_cost) ||
        !is_finite(n.bounds.lo) || !is_finite(n.bounds.hi))
      r.fail("invalid merge node");
  }
  h.initial_cost = r.get<double>();
  h.total_weight = r.get<double>();
  h.cost_after.resize(nodes - h.leaf_count);
  for (double& c : h.cost_after) {
    c = r.get<double>();
    if (!std::isfinite(c)) r.fail("invalid cost in the merge history");
  }
  // Structure: leaves first; merge k is node L + k, made of two earlier nodes.
  const int32_t L = static_cast<int32_t>(h.leaf_count);
  for (int32_t i = 0; i < static_cast<int32_t>(nodes); ++i) {
    const MergeNode& n = h.nodes[i];
    const bool leaf = i < L;
    if (leaf != (n.child[0] < 0) || leaf != (n.child[1] < 0)) r.fail("merge node " + std::to_string(i) + " is malformed");
    if (n.parent != -1 && (n.parent <= i || n.parent >= static_cast<int32_t>(nodes) ||
                           (h.nodes[n.parent].child[0] != i && h.nodes[n.parent].child[1] != i)))
      r.fail("merge node " + std::to_string(i) + " has a wrong parent");
    if (!leaf)
      for (int32_t c : n.child)
        if (c >= i || h.nodes[c].parent != i) r.fail("merge node " + std::to_string(i) + " has a wrong child");
    if (leaf && n.pvs_size != leaf_pvs[leaves[i]].size()) r.fail("merge leaf " + std::to_string(i) + " has another PVS");
  }
  return h;
}

}  // namespace

void write_subdivision(const std::string& path, const SubdivisionFile& f) {
  const Subdivision& s = f.subdivision;
  ByteWriter w;
  w.put(s.view_box.lo);
  w.put(s.view_box.hi);
  w.put(f.cost_model.a);
  w.put(f.cost_model.b);
  w.put(f.cost_model.c);
  w.put<int32_t>(f.cost_model.screen_width);
  w.put<int32_t>(f.cost_model.screen_height);
  w.put(f.cost_model.fov_degrees);
  w.put<uint64_t>(f.scene_fingerprint);
  w.put<uint32_t>(f.object_count);
  w.put(s.initial_cost);
  put_planes(w, s.planes);
  w.put<uint64_t>(s.nodes.size());
  for (const BspNode& n : s.nodes) {
    w.put<int32_t>(n.plane);
    w.put<int32_t>(n.child[0]);
    w.put<int32_t>(n.child[1]);
    w.put<int32_t>(n.parent);
    w.put(n.volume);
    w.put(n.weight);
    w.put(n.pvs_cost);
  }
  w.put<uint64_t>(s.splits.size());
  for (const SplitRecord& r : s.splits) {
    w.put<int32_t>(r.node);
    w.put(r.reduction);
    w.put(r.cost_after);
  }
  for (size_t n = 0; n < s.nodes.size(); ++n) w.put_array(n < f.leaf_pvs.size() ? f.leaf_pvs[n] : std::vector<uint32_t>{});
  put_history(w, f.history);
  if (!f.object_names.empty() && f.object_names.size() != f.object_count)
    throw Error(path, 0, "object names do not match the object count");
  w.put<uint64_t>(f.object_names.size());
  for (const std::string& n : f.object_names) w.put_string(n);
  write_container(path, kMagic, kVersion, w.data());
}

SubdivisionFile read_subdivision(const std::string& path) {
  uint32_t version = 0;
  const std::string payload = read_container(path, kMagic, kVersion, version);
  ByteReader r(payload, path);
  SubdivisionFile f;
  Subdivision& s = f.subdivision;
  s.view_box = get_view_box(r);
  f.cost_model.a = r.get<double>();
  f.cost_model.b = r.get<double>();
  f.cost_model.c = r.get<double>();
  if (version >= 2) {
    f.cost_model.screen_width = r.get<int32_t>();
    f.cost_model.screen_height = r.get<int32_t>();
    f.cost_model.fov_degrees = r.get<double>();
  }
  try {
    f.cost_model.validate();
  } catch (const Error& e) {
    r.fail(std::string("invalid cost model (") + e.what() + ")");
  }
  f.scene_fingerprint = r.get<uint64_t>();
  f.object_count = r.get<uint32_t>();
  s.initial_cost = r.get<double>();
  const uint64_t max_items = payload.size() / 8;
  s.planes = get_planes(r, max_items);
  const uint64_t planes = s.planes.size();
  const uint64_t nodes = r.get<uint64_t>();
  if (nodes == 0 || nodes > max_items || nodes % 2 == 0) r.fail("invalid node count");
  s.nodes.resize(nodes);
  for (BspNode& n : s.nodes) {
    n.plane = r.get<int32_t>();
    n.child[0] = r.get<int32_t>();
    n.child[1] = r.get<int32_t>();
    n.parent = r.get<int32_t>();
    n.volume = r.get<double>();
    n.weight = r.get<double>();
    n.pvs_cost = r.get<double>();
  }
  const uint64_t splits = r.get<uint64_t>();
  if (splits > max_items || 2 * splits + 1 != nodes) r.fail("split count does not match the node count");
  s.splits.resize(splits);
  for (SplitRecord& rec : s.splits) {
    rec.node = r.get<int32_t>();
    rec.reduction = r.get<double>();
    rec.cost_after = r.get<double>();
  }
  f.leaf_pvs.resize(nodes);
  for (auto& pvs : f.leaf_pvs) r.get_array(pvs, max_items);
  const size_t history_at = r.position();
  // Structure: split k splits an existing leaf into nodes 2k+1 and 2k+2 on plane 6 + k.
  const int32_t n_nodes = static_cast<int32_t>(nodes);
  if (s.nodes[0].parent != -1) r.fail("the root has a parent");
  for (size_t k = 0; k < splits; ++k) {
    const int32_t node = s.splits[k].node;
    if (node < 0 || node > static_cast<int32_t>(2 * k)) r.fail("split " + std::to_string(k) + " names a node not yet created");
    const BspNode& n = s.nodes[node];
    const int32_t c0 = static_cast<int32_t>(2 * k + 1), c1 = c0 + 1;
    if (n.plane != static_cast<int32_t>(6 + k) || n.child[0] != c0 || n.child[1] != c1 || s.nodes[c0].parent != node ||
        s.nodes[c1].parent != node)
      r.fail("split " + std::to_string(k) + " does not match the tree");
  }
  for (int32_t i = 0; i < n_nodes; ++i) {
    const BspNode& n = s.nodes[i];
    if (n.plane >= static_cast<int32_t>(planes) || !(n.volume > 0) || !(n.weight >= 0) || !(n.pvs_cost >= 0))
      r.fail("node " + std::to_string(i) + " is invalid");
    if (n.plane < 0 && (n.child[0] != -1 || n.child[1] != -1)) r.fail("leaf " + std::to_string(i) + " has children");
    for (uint32_t o : f.leaf_pvs[i])
      if (o >= f.object_count) r.fail("node " + std::to_string(i) + " lists object " + std::to_string(o));
    if (!std::is_sorted(f.leaf_pvs[i].begin(), f.leaf_pvs[i].end())) r.fail("unsorted PVS");
  }
  if (planes != 6 + splits) r.fail("plane count does not match the split count");
  if (!(s.nodes[0].weight > 0)) r.fail("the view space has zero weight");
  if (version >= 3) {
    r.seek(history_at);
    f.history = get_history(r, s, f.leaf_pvs, max_items);
    const uint64_t names = r.get<uint64_t>();
    if (names != 0 && names != f.object_count) r.fail("object names do not match the object count");
    for (uint64_t i = 0; i < names; ++i) f.object_names.push_back(r.get_string());
  }
  if (!r.at_end()) r.fail("trailing bytes");
  return f;
}

void rebuild_cells(Subdivision& s) {
  s.cells.assign(s.nodes.size(), ConvexPolyhedron());
  s.cells[0] = ConvexPolyhedron::box(s.view_box, 0);
  for (const SplitRecord& r : s.splits) {
    const BspNode& n = s.nodes[r.node];
    auto halves = s.cells[r.node].split(s.planes[n.plane], n.plane);
    if (!halves) throw Error("replaying split of node " + std::to_string(r.node) + " failed (corrupt file?)");
    s.cells[n.child[0]] = std::move(halves->first);
    s.cells[n.child[1]] = std::move(halves->second);
    s.cells[r.node] = ConvexPolyhedron();
  }
}

namespace {

/// Blue -> cyan -> green -> yellow -> red for t in [0, 1].
void cost_colour(double t, unsigned char rgb[3]) {
  t = std::clamp(t, 0.0, 1.0);
  const double r = std::clamp(std::min(4 * t - 1.5, -4 * t + 4.5), 0.0, 1.0);
  const double g = std::clamp(std::min(4 * t - 0.5, -4 * t + 3.5), 0.0, 1.0);
  const double b = std::clamp(std::min(4 * t + 0.5, -4 * t + 2.5), 0.0, 1.0);
  rgb[0] = static_cast<unsigned char>(255 * r);
  rgb[1] = static_cast<unsigned char>(255 * g);
  rgb[2] = static_cast<unsigned char>(255 * b);
}

double max_leaf_value(const Subdivision& s, const CellView* view) {
  double m = 0;
  for (int32_t l : s.leaves()) m = std::max(m, view ? view->value[l] : s.nodes[l].pvs_cost);
  return m > 0 ? m : 1.0;
}

void check_view(const Subdivision& s, const CellView* view) {
  if (view && (view->value.size() != s.nodes.size() || view->group.size() != s.nodes.size()))
    throw Error("cell view does not match the subdivision");
}

}  // namespace

CellView merged_cell_view(const Subdivision& s, const MergeHistory& h, const std::vector<int32_t>& cells) {
  const std::vector<int32_t> leaves = s.leaves();
  if (leaves.size() != h.leaf_count) throw Error("the merge history does not match the subdivision");
  CellView view;
  view.value.assign(s.nodes.size(), 0.0);
  view.group.assign(s.nodes.size(), -1);
  for (int32_t c : cells)
    for (uint32_t leaf : h.leaves_under(c)) {
      view.value[leaves[leaf]] = h.nodes[c].pvs_cost;
      view.group[leaves[leaf]] = c;
    }
  return view;
}

void write_cells_ply(const std::string& path, const Subdivision& s, const CellView* view, double shrink) {
  check_view(s, view);
  const std::vector<int32_t> leaves = s.leaves();
  const double max_cost = max_leaf_value(s, view);
  std::string body;
  size_t nv = 0, nf = 0;
  std::string faces;
  for (int32_t l : leaves) {
    const ConvexPolyhedron& cell = s.cells[l];
    if (cell.empty()) throw Error(path, 0, "cell geometry missing (rebuild_cells first)");
    unsigned char rgb[3];
    cost_colour((view ? view->value[l] : s.nodes[l].pvs_cost) / max_cost, rgb);
    const Vec3 c = cell.centroid();
    const size_t base = nv;
    for (const Vec3& p : cell.vertices()) {
      const Vec3 q = c + (p - c) * shrink;
      const float xyz[3] = {static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)};
      body.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
      body.append(reinterpret_cast<const char*>(rgb), 3);
      ++nv;
    }
    for (const PolyFace& f : cell.faces()) {
      const unsigned char count = static_cast<unsigned char>(std::min<size_t>(f.vertices.size(), 255));
      faces.push_back(static_cast<char>(count));
      for (size_t k = 0; k < count; ++k) {
        const int32_t id = static_cast<int32_t>(base + f.vertices[k]);
        faces.append(reinterpret_cast<const char*>(&id), 4);
      }
      ++nf;
    }
  }
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment viewcells: cells coloured by render cost\n";
  header += "element vertex " + std::to_string(nv) +
            "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
            "property uchar blue\nelement face " +
            std::to_string(nf) + "\nproperty list uchar int vertex_indices\nend_header\n";
  write_text_file(path, header + body + faces);
}

void write_slice_png(const std::string& path, const Subdivision& s, double height, int width, const Scene* scene,
                     const CellView* view) {
  check_view(s, view);
  const Box3& b = s.view_box;
  if (!(height >= b.lo.z && height <= b.hi.z))
    throw Error("slice height " + std::to_string(height) + " is outside the view space (" + std::to_string(b.lo.z) +
                " to " + std::to_string(b.hi.z) + ")");
  if (width < 16 || width > 16384) throw Error("slice width must be between 16 and 16384 pixels");
  const double scale = width / (b.hi.x - b.lo.x);
  const int h = std::max(16, static_cast<int>(std::ceil((b.hi.y - b.lo.y) * scale)));
  const double max_cost = max_leaf_value(s, view);
  std::vector<int32_t> leaf(static_cast<size_t>(width) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < width; ++x)
      leaf[static_cast<size_t>(y) * width + x] =
          s.locate({b.lo.x + (x + 0.5) / scale, b.hi.y - (y + 0.5) / scale, height});
  // Borders are drawn where the cell changes: the leaf, or the group of the view.
  auto cell_of = [&](int32_t l) { return view && l >= 0 ? view->group[l] : l; };
  std::vector<unsigned char> rgb(static_cast<size_t>(width) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      unsigned char* px = &rgb[3 * i];
      const int32_t l = leaf[i];
      cost_colour(l >= 0 ? (view ? view->value[l] : s.nodes[l].pvs_cost) / max_cost : 0.0, px);
      const int32_t cell = cell_of(l);
      const bool border =
          (x + 1 < width && cell_of(leaf[i + 1]) != cell) || (y + 1 < h && cell_of(leaf[i + width]) != cell);
      if (border)
        for (int c = 0; c < 3; ++c) px[c] = static_cast<unsigned char>(px[c] / 3);
    }
  if (scene) {
    // The scene's cross-section: where triangles cross z = height, drawn in black.
    auto plot = [&](double wx, double wy) {
      const int x = static_cast<int>((wx - b.lo.x) * scale), y = static_cast<int>((b.hi.y - wy) * scale);
      if (x >= 0 && x < width && y >= 0 && y < h) std::memset(&rgb[3 * (static_cast<size_t>(y) * width + x)], 0, 3);
    };
    for (const auto& tri : scene->triangles) {
      Vec3 pts[2];
      int k = 0;
      for (int e = 0; e < 3 && k < 2; ++e) {
        const Vec3 p = scene->vertices[tri[e]], q = scene->vertices[tri[(e + 1) % 3]];
        if ((p.z - height) * (q.z - height) < 0) pts[k++] = p + (q - p) * ((height - p.z) / (q.z - p.z));
      }
      if (k < 2) continue;
      const double len = length(pts[1] - pts[0]) * scale;
      const int steps = std::max(1, static_cast<int>(len * 2));
      for (int i = 0; i <= steps; ++i) {
        const Vec3 p = pts[0] + (pts[1] - pts[0]) * (static_cast<double>(i) / steps);
        plot(p.x, p.y);
      }
    }
  }
  check_output_target(path);
  const std::string tmp = temporary_for(path);
  FILE* fp = std::fopen(tmp.c_str(), "wb");
  if (!fp) throw Error(path, 0, "cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(fp);
    std::remove(tmp.c_str());
    throw Error(path, 0, "PNG encoding failed");
  }
  png_init_io(png, fp);
  png_set_IHDR(png, info, width, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < h; ++y) png_write_row(png, &rgb[3 * static_cast<size_t>(y) * width]);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(fp) != 0) {
    std::remove(tmp.c_str());
    throw Error(path, 0, "cannot write PNG");
  }
  install_file(tmp, path);
}

}  // namespace viewcells
