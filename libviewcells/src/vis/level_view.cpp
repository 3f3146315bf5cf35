/// View cells and their PVSs as glTF 2.0 and as the static web page (three.js) for people to look
/// at.
#include "viewcells/vis/level_view.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/vis/cell_views.h"
#include "web_assets.h"

namespace viewcells {

using json = nlohmann::json;

namespace {

constexpr double kShrink = 0.97;  // as the PLY view: neighbouring leaves stay apart

/// glTF and the web page store positions as floats: a vertex beyond their range would be
/// written as inf (a .glb whose accessor bounds are null), so it is an error instead.
void push_vertex(GroupedMesh& m, const Vec3& p) {
  const float xyz[3] = {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
  if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
    throw Error("view: a vertex at (" + fmt(p.x) + ", " + fmt(p.y) + ", " + fmt(p.z) +
                ") is not finite in float, in which glTF and the web page store positions (is the view box beyond "
                "+-3.4e38?)");
  m.positions.insert(m.positions.end(), xyz, xyz + 3);
}

void close_group(GroupedMesh& m) {
  m.first_vertex.push_back(static_cast<uint32_t>(m.positions.size() / 3));
  m.first_index.push_back(static_cast<uint32_t>(m.indices.size()));
}

/// The leaves of every view cell as triangles, cell after cell. A .pvs file keeps the BSP's tree
/// but not its split order, so the leaves are found by clipping the view box down the tree.
GroupedMesh cell_mesh(const Subdivision& bsp, const std::vector<int32_t>& leaf_cell, uint32_t cell_count) {
  std::vector<ConvexPolyhedron> leaf_poly(bsp.nodes.size());
  std::vector<std::vector<int32_t>> leaves_of(cell_count);
  clip_to_leaves(bsp, ConvexPolyhedron::box(bsp.view_box, 0), [&](int32_t leaf, const ConvexPolyhedron& part) {
    const int32_t c = leaf_cell[leaf];
    if (c < 0 || static_cast<uint32_t>(c) >= cell_count) return;
    leaf_poly[leaf] = part;
    leaves_of[c].push_back(leaf);
  });
  GroupedMesh m;
  m.first_vertex.push_back(0);
  m.first_index.push_back(0);
  for (uint32_t c = 0; c < cell_count; ++c) {
    for (int32_t leaf : leaves_of[c]) {
      const ConvexPolyhedron& poly = leaf_poly[leaf];
      const Vec3 centre = poly.centroid();
      const uint32_t base = static_cast<uint32_t>(m.positions.size() / 3);
      for (const Vec3& p : poly.vertices()) push_vertex(m, centre + (p - centre) * kShrink);
      for (const PolyFace& f : poly.faces())
        for (size_t k = 1; k + 1 < f.vertices.size(); ++k)
          m.indices.insert(m.indices.end(), {base + f.vertices[0], base + f.vertices[k], base + f.vertices[k + 1]});
    }
    close_group(m);
  }
  return m;
}

/// The scene's triangles object after object, each object with vertices of its own (so that a
/// viewer can colour an object by its vertex range).
GroupedMesh scene_mesh(const Scene& scene) {
  std::vector<std::vector<uint32_t>> tris_of(scene.object_count());
  for (uint32_t t = 0; t < scene.triangle_count(); ++t) tris_of[scene.triangle_object[t]].push_back(t);
  GroupedMesh m;
  m.first_vertex.push_back(0);
  m.first_index.push_back(0);
  std::vector<uint32_t> local(scene.vertices.size(), UINT32_MAX);
  for (const auto& tris : tris_of) {
    std::vector<uint32_t> used;
    for (uint32_t t : tris) {
      for (uint32_t v : scene.triangles[t]) {
        if (local[v] == UINT32_MAX) {
          local[v] = static_cast<uint32_t>(m.positions.size() / 3);
          used.push_back(v);
          push_vertex(m, scene.vertices[v]);
        }
        m.indices.push_back(local[v]);
      }
    }
    for (uint32_t v : used) local[v] = UINT32_MAX;
    close_group(m);
  }
  return m;
}

std::string base64(const void* data, size_t size) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = static_cast<const uint8_t*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (size_t i = 0; i < size; i += 3) {
    uint32_t v = uint32_t(b[i]) << 16;
    if (i + 1 < size) v |= uint32_t(b[i + 1]) << 8;
    if (i + 2 < size) v |= b[i + 2];
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < size ? k[(v >> 6) & 63] : '=';
    out += i + 2 < size ? k[v & 63] : '=';
  }
  return out;
}

template <class T>
std::string base64(const std::vector<T>& v) {
  return base64(v.data(), v.size() * sizeof(T));
}

std::array<double, 3> colour_of(double t) {
  unsigned char rgb[3];
  cost_colour(t, rgb);
  return {rgb[0] / 255.0, rgb[1] / 255.0, rgb[2] / 255.0};
}

/// glTF 2.0 binary: accessors and buffer views appended as the meshes are written.
class GlbBuilder {
 public:
  /// A mesh of group g of m (indices made local), with `material`; returns the mesh index.
  int add_mesh(const GroupedMesh& m, size_t g, int material) {
    const uint32_t v0 = m.first_vertex[g], v1 = m.first_vertex[g + 1];
    const uint32_t i0 = m.first_index[g], i1 = m.first_index[g + 1];
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    // glTF is y-up (glTF 2.0, 3.4): (x, y, z) -> (x, z, -y).
    std::vector<float> yup((v1 - v0) * 3);
    for (uint32_t v = v0; v < v1; ++v) {
      yup[3 * (v - v0)] = m.positions[3 * v];
      yup[3 * (v - v0) + 1] = m.positions[3 * v + 2];
      yup[3 * (v - v0) + 2] = -m.positions[3 * v + 1];
    }
    for (uint32_t v = 0; v < v1 - v0; ++v)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], yup[3 * v + k]);
        hi[k] = std::max(hi[k], yup[3 * v + k]);
      }
    const int pos = add_view(yup.data(), yup.size() * sizeof(float), 34962);
    accessors_.push_back({{"bufferView", pos}, {"componentType", 5126}, {"count", v1 - v0}, {"type", "VEC3"},
                          {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
    std::vector<uint32_t> local(m.indices.begin() + i0, m.indices.begin() + i1);
    for (uint32_t& i : local) i -= v0;
    const int idx = add_view(local.data(), local.size() * sizeof(uint32_t), 34963);
    accessors_.push_back({{"bufferView", idx}, {"componentType", 5125}, {"count", local.size()}, {"type", "SCALAR"}});
    const int n = static_cast<int>(accessors_.size());
    meshes_.push_back({{"primitives", json::array({{{"attributes", {{"POSITION", n - 2}}},
                                                    {"indices", n - 1},
                                                    {"material", material}}})}});
    return static_cast<int>(meshes_.size()) - 1;
  }

  int add_material(const std::string& name, const std::array<double, 3>& rgb, double alpha) {
    json m = {{"name", name},
              {"pbrMetallicRoughness",
               {{"baseColorFactor", {rgb[0], rgb[1], rgb[2], alpha}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.9}}},
              {"doubleSided", alpha < 1}};
    if (alpha < 1) m["alphaMode"] = "BLEND";
    materials_.push_back(m);
    return static_cast<int>(materials_.size()) - 1;
  }

  int add_node(json node) {
    nodes_.push_back(std::move(node));
    return static_cast<int>(nodes_.size()) - 1;
  }
  json& node(int i) { return nodes_[i]; }

  std::string glb(const std::vector<int>& roots, json asset_extras) const {
    json doc = {{"asset", {{"version", "2.0"}, {"generator", "viewcells"}, {"extras", std::move(asset_extras)}}},
                {"scene", 0},
                {"scenes", json::array({{{"nodes", roots}}})},
                {"nodes", nodes_},
                {"materials", materials_},
                {"accessors", accessors_},
                {"bufferViews", views_}};
    if (!meshes_.empty()) doc["meshes"] = meshes_;
    if (!bin_.empty()) doc["buffers"] = json::array({{{"byteLength", bin_.size()}}});
    std::string text = doc.dump();
    while (text.size() % 4) text += ' ';
    std::string bin = bin_;
    while (bin.size() % 4) bin += '\0';
    std::string out;
    auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    const bool has_bin = !bin.empty();
    out.reserve(12 + 8 + text.size() + (has_bin ? 8 + bin.size() : 0));
    out += "glTF";
    u32(2);
    u32(static_cast<uint32_t>(12 + 8 + text.size() + (has_bin ? 8 + bin.size() : 0)));
    u32(static_cast<uint32_t>(text.size()));
    out += "JSON";
    out += text;
    if (has_bin) {
      u32(static_cast<uint32_t>(bin.size()));
      out.append("BIN\0", 4);
      out += bin;
    }
    return out;
  }

 private:
  int add_view(const void* data, size_t bytes, int target) {
    views_.push_back({{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}, {"target", target}});
    bin_.append(static_cast<const char*>(data), bytes);
    return static_cast<int>(views_.size()) - 1;
  }

  json nodes_ = json::array(), meshes_ = json::array(), materials_ = json::array(), accessors_ = json::array(),
       views_ = json::array();
  std::string bin_;
};

double max_of(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, x);
  return m > 0 ? m : 1.0;
}

}  // namespace

LevelView make_level_view(PvsFile f, const Scene& scene, const CostModel& model) {
  if (scene.fingerprint() != f.scene_fingerprint)
    throw Error(scene.source, 0, "is not the scene the .pvs file was made for (fingerprints differ)");
  if (scene.object_count() != f.object_count) throw Error(scene.source, 0, "object count differs from the .pvs file's");
  LevelView v;
  v.model = model;
  v.model.c = 0;
  v.scene_source = scene.source;
  v.object_cost = per_object_costs(scene, v.model);
  v.cells = cell_mesh(f.bsp, f.leaf_cell, f.pvs.cell_count);
  v.scene = scene_mesh(scene);
  for (uint32_t c = 0; c < f.pvs.cell_count; ++c) {
    v.pvs.push_back(f.pvs.cell_pvs(c));
    double cost = 0;
    for (uint32_t o : v.pvs.back()) cost += v.object_cost[o];
    v.cell_cost.push_back(cost);
  }
  for (const ObjectInfo& o : scene.objects) {
    v.object_triangles.push_back(o.triangle_count);
    v.object_see_through.push_back(o.occluder ? 0 : 1);
    v.object_names.push_back(o.name);
  }
  v.file = std::move(f);
  return v;
}

void write_level_gltf(const std::string& path, const LevelView& view) {
  check_output_target(path);
  GlbBuilder b;
  const int grey = b.add_material("scene", {0.75, 0.75, 0.72}, 1.0);
  const int glass = b.add_material("scene see-through", {0.6, 0.8, 0.95}, 0.4);
  std::vector<int> objects;
  for (size_t o = 0; o < view.scene.group_count(); ++o) {
    if (view.scene.first_index[o] == view.scene.first_index[o + 1]) continue;
    const int mesh = b.add_mesh(view.scene, o, view.object_see_through[o] ? glass : grey);
    objects.push_back(b.add_node({{"name", view.object_names[o]}, {"mesh", mesh}, {"extras", {{"object", o}}}}));
  }
  const double max_cost = max_of(view.cell_cost);
  std::vector<int> cells;
  for (size_t c = 0; c < view.cells.group_count(); ++c) {
    if (view.cells.first_index[c] == view.cells.first_index[c + 1]) continue;
    const int material = b.add_material("cell " + std::to_string(c), colour_of(view.cell_cost[c] / max_cost), 0.35);
    const int mesh = b.add_mesh(view.cells, c, material);
    cells.push_back(b.add_node({{"name", "cell " + std::to_string(c)},
                                {"mesh", mesh},
                                {"extras",
                                 {{"cell", c},
                                  {"render_cost", view.cell_cost[c]},
                                  {"pvs_size", view.pvs[c].size()},
                                  {"pvs", view.pvs[c]}}}}));
  }
  const int scene_root = b.add_node({{"name", "scene"}, {"children", objects}});
  const int cell_root = b.add_node({{"name", "view cells"}, {"children", cells}});
  if (objects.empty()) b.node(scene_root).erase("children");
  if (cells.empty()) b.node(cell_root).erase("children");
  std::vector<int> roots = {scene_root, cell_root};
  if (view.play_space.group_count() == 1 && !view.play_space.indices.empty()) {
    const int green = b.add_material("play space", {0.2, 0.85, 0.3}, 0.5);
    roots.push_back(b.add_node({{"name", "play space"},
                                {"mesh", b.add_mesh(view.play_space, 0, green)},
                                {"extras", {{"rule", view.play_space_rule}}}}));
  }
  const json extras = {{"viewcells",
                        {{"scene", view.scene_source},
                         {"rule", view.file.rule},
                         {"cells", view.file.pvs.cell_count},
                         {"cost_model", {{"a", view.model.a}, {"b", view.model.b}}},
                         {"objects", view.object_names}}}};
  write_text_file(path, b.glb(roots, extras));
}

void write_scene_gltf(const std::string& path, const Scene& scene, const SceneGltfOptions& options) {
  const double k = options.metres_per_unit;
  if (!(k > 0 && std::isfinite(k))) throw Error(path, 0, "metres per unit must be positive");
  check_output_target(path);
  GroupedMesh m = scene_mesh(scene);
  for (float& x : m.positions) x = static_cast<float>(x * k);
  GlbBuilder b;
  const int grey = b.add_material("scene", {0.75, 0.75, 0.72}, 1.0);
  const int glass = b.add_material("scene see-through", {0.6, 0.8, 0.95}, 0.4);
  std::vector<int> roots;
  for (size_t o = 0; o < m.group_count(); ++o) {
    const ObjectInfo& info = scene.objects[o];
    const bool kept = options.keep.empty() ? info.rendered : o < options.keep.size() && options.keep[o];
    if (!kept || m.first_index[o] == m.first_index[o + 1]) continue;
    roots.push_back(b.add_node({{"name", info.name}, {"mesh", b.add_mesh(m, o, info.occluder ? grey : glass)}}));
  }
  for (size_t i = 0; i < options.start_points.size(); ++i) {
    const Vec3 p = options.start_points[i] * k;  // y-up, as the meshes
    roots.push_back(b.add_node({{"name", "spawn " + std::to_string(i + 1)}, {"translation", {p.x, p.z, -p.y}}}));
  }
  write_text_file(path, b.glb(roots, json{{"viewcells", {{"source", scene.source}}}}));
}

void require_web_viewer() {
  if (!web_assets::available())
    throw Error(
        "this viewcells was built without the web viewer (web/node_modules was missing): run "
        "scripts/install-deps.sh, then build again");
}

void write_web_viewer(const std::string& dir, const LevelView& view) {
  require_web_viewer();
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    throw Error(dir, 0, "exists and is not a directory");
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir, 0, "cannot create the directory: " + ec.message());
  const Subdivision& bsp = view.file.bsp;
  json planes = json::array(), nodes = json::array();
  for (const Plane& p : bsp.planes) planes.push_back({p.normal.x, p.normal.y, p.normal.z, p.offset, p.axis});
  for (const BspNode& n : bsp.nodes) nodes.push_back({n.plane, n.child[0], n.child[1]});
  std::vector<float> cost(view.cell_cost.begin(), view.cell_cost.end());
  std::vector<float> object_cost(view.object_cost.begin(), view.object_cost.end());
  const Box3& box = bsp.view_box;
  const json data = {
      {"format", 1},
      {"scene", view.scene_source},
      {"rule", view.file.rule},
      {"cost_model", {{"a", view.model.a}, {"b", view.model.b}}},
      {"view_box", {box.lo.x, box.lo.y, box.lo.z, box.hi.x, box.hi.y, box.hi.z}},
      {"bsp", {{"planes", planes}, {"nodes", nodes}, {"leaf_cell", view.file.leaf_cell}}},
      {"objects",
       {{"count", view.object_names.size()},
        {"names", view.object_names},
        {"triangles", base64(view.object_triangles)},
        {"cost", base64(object_cost)},
        {"see_through", base64(view.object_see_through)},
        {"positions", base64(view.scene.positions)},
        {"indices", base64(view.scene.indices)},
        {"first_vertex", base64(view.scene.first_vertex)},
        {"first_index", base64(view.scene.first_index)}}},
      {"cells",
       {{"count", view.pvs.size()},
        {"pvs", view.pvs},
        {"cost", base64(cost)},
        {"positions", base64(view.cells.positions)},
        {"indices", base64(view.cells.indices)},
        {"first_vertex", base64(view.cells.first_vertex)},
        {"first_index", base64(view.cells.first_index)}}},
      {"play_space",
       {{"rule", view.play_space_rule},
        {"positions", base64(view.play_space.positions)},
        {"indices", base64(view.play_space.indices)}}}};
  const std::filesystem::path d(dir);
  write_text_file((d / "data.js").string(), "window.VIEWCELLS_DATA = " + data.dump() + ";\n");
  write_text_file((d / "viewer.js").string(), web_assets::viewer_js());
  write_text_file((d / "index.html").string(), web_assets::index_html());
}

}  // namespace viewcells
