/// The scene: objects from triangles, their bounds, areas and closedness (the precondition of empty
/// view space detection, paper 4.1).
#include "viewcells/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "viewcells/core/error.h"
#include "viewcells/core/names.h"
#include "viewcells/core/union_find.h"
#include "viewcells/core/rng.h"

namespace viewcells {

namespace {
constexpr EnumNames<ObjectGrouping, 6> kGroupingNames{{{{ObjectGrouping::kAuto, "auto"},
                                                        {ObjectGrouping::kGroups, "groups"},
                                                        {ObjectGrouping::kComponents, "components"},
                                                        {ObjectGrouping::kTriangles, "triangles"},
                                                        {ObjectGrouping::kNodes, "nodes"},
                                                        {ObjectGrouping::kMeshes, "meshes"}}},
                                                      "object grouping"};
}  // namespace

ObjectGrouping parse_grouping(const std::string& name) { return kGroupingNames.parse(name); }

const char* to_string(ObjectGrouping g) { return kGroupingNames.name(g); }

namespace {

struct Vec3Hash {
  size_t operator()(const Vec3& v) const {
    uint64_t h = 0;
    for (double c : {v.x, v.y, v.z}) {
      if (c == 0.0) c = 0.0;  // -0 and +0 weld together
      uint64_t bits;
      std::memcpy(&bits, &c, sizeof bits);
      h = mix64(h ^ bits);
    }
    return static_cast<size_t>(h);
  }
};

/// Vertex ids welded by exact position, so that STL-like soups and duplicated OBJ vertices
/// still count as connected.
std::vector<uint32_t> weld_positions(const std::vector<Vec3>& vertices) {
  std::unordered_map<Vec3, uint32_t, Vec3Hash> ids;
  ids.reserve(vertices.size());
  std::vector<uint32_t> welded(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Vec3 key{vertices[i].x + 0.0, vertices[i].y + 0.0, vertices[i].z + 0.0};
    welded[i] = ids.emplace(key, static_cast<uint32_t>(ids.size())).first->second;
  }
  return welded;
}

bool is_degenerate(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  const double longest = std::max({dot(b - a, b - a), dot(c - a, c - a), dot(c - b, c - b)});
  // Zero area, up to rounding of the cross product relative to the edge lengths.
  return !(dot(n, n) > 1e-24 * longest * longest);
}

bool axis_aligned_normal(const Vec3& n) {
  const double l = length(n);
  const double ax = std::abs(n.x) / l, ay = std::abs(n.y) / l, az = std::abs(n.z) / l;
  return std::max({ax, ay, az}) > 1.0 - 1e-9;
}

}  // namespace

void Scene::finalize() {
  bounds = Box3{};
  for (const auto& v : vertices) bounds.extend(v);
  surface_area = 0;
  non_axis_aligned_area = 0;
  for (auto& o : objects) {
    o.triangle_count = 0;
    o.bounds = Box3{};
    o.surface_area = 0;
    o.signed_volume = 0;
    o.closed = o.oriented = false;
  }
  for (size_t t = 0; t < triangles.size(); ++t) {
    ObjectInfo& o = objects[triangle_object[t]];
    const auto& tri = triangles[t];
    const Vec3 n = triangle_normal(static_cast<uint32_t>(t));
    const double area = 0.5 * length(n);
    ++o.triangle_count;
    for (uint32_t v : tri) o.bounds.extend(vertices[v]);
    o.surface_area += area;
    surface_area += area;
    if (!axis_aligned_normal(n)) non_axis_aligned_area += area;
    // Any reference point gives the same volume for a closed mesh; a central one keeps the
    // rounding small when coordinates are large (cities at 1e5).
    const Vec3 c = bounds.center();
    o.signed_volume += dot(vertices[tri[0]] - c, cross(vertices[tri[1]] - c, vertices[tri[2]] - c)) / 6.0;
  }

  // Closedness: every welded undirected edge of an object used exactly twice, once per direction.
  const std::vector<uint32_t> welded = weld_positions(vertices);
  struct EdgeUse { uint32_t forward = 0, backward = 0; };
  std::vector<std::unordered_map<uint64_t, EdgeUse>> edges(objects.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    auto& map = edges[triangle_object[t]];
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = welded[triangles[t][e]], b = welded[triangles[t][(e + 1) % 3]];
      const uint64_t key = (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      EdgeUse& use = map[key];
      (a < b ? use.forward : use.backward)++;
    }
  }
  all_solid = !objects.empty();
  for (size_t i = 0; i < objects.size(); ++i) {
    ObjectInfo& o = objects[i];
    bool closed = o.triangle_count > 0, oriented = closed;
    for (const auto& [key, use] : edges[i]) {
      if (use.forward + use.backward != 2) closed = false;
      if (use.forward != 1 || use.backward != 1) oriented = false;
    }
    o.closed = closed;
    o.oriented = closed && oriented;
    all_solid = all_solid && o.solid();
  }
}

uint64_t Scene::fingerprint() const {
  uint64_t h = mix64(vertices.size()) ^ mix64(triangles.size() + 1) ^ mix64(objects.size() + 2);
  auto feed = [&h](const void* p, size_t n) {
    const auto* bytes = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; i += 8) {
      uint64_t w = 0;
      std::memcpy(&w, bytes + i, std::min<size_t>(8, n - i));
      h = mix64(h ^ w);
    }
  };
  feed(vertices.data(), vertices.size() * sizeof(Vec3));
  feed(triangles.data(), triangles.size() * sizeof(triangles[0]));
  feed(triangle_object.data(), triangle_object.size() * sizeof(uint32_t));
  return h;
}

Scene make_scene(RawMesh mesh, ObjectGrouping grouping, const std::string& source) {
  Scene scene;
  scene.source = source;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!is_finite(mesh.vertices[i]))
      throw Error(source, 0, "vertex " + std::to_string(i + 1) + " has a NaN or infinite coordinate");
  }
  const bool has_groups = !mesh.group_names.empty();
  if (grouping == ObjectGrouping::kAuto)
    grouping = has_groups ? ObjectGrouping::kGroups : ObjectGrouping::kComponents;
  scene.grouping = grouping;

  // Keep non-degenerate triangles.
  std::vector<uint32_t> kept_group;
  scene.triangles.reserve(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (uint32_t v : tri)
      if (v >= mesh.vertices.size())
        throw Error(source, 0, "triangle " + std::to_string(t + 1) + " references vertex " +
                                   std::to_string(v + 1) + " of " + std::to_string(mesh.vertices.size()));
    if (is_degenerate(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]])) {
      ++scene.degenerate_dropped;
      continue;
    }
    scene.triangles.push_back(tri);
    kept_group.push_back(has_groups ? mesh.triangle_group[t] : 0);
  }
  scene.vertices = std::move(mesh.vertices);
  scene.metres_per_unit = mesh.metres_per_unit;
  for (const Vec3& p : mesh.start_points)
    if (!is_finite(p)) throw Error(source, 0, "a start point has a NaN or infinite coordinate");
  scene.start_points = std::move(mesh.start_points);

  const size_t n = scene.triangles.size();
  scene.triangle_object.resize(n);
  switch (grouping) {
    case ObjectGrouping::kAuto:  // resolved above
    case ObjectGrouping::kNodes:  // the Assimp reader made one group per node (or mesh)
    case ObjectGrouping::kMeshes:
    case ObjectGrouping::kGroups: {
      // Objects in order of first appearance; groups that lost all triangles vanish (unless the
      // caller's ids are kept: then every group is the object of its index).
      std::vector<uint32_t> remap(std::max<size_t>(mesh.group_names.size(), 1), kNoObject);
      if (mesh.keep_group_ids && has_groups)
        for (uint32_t g = 0; g < mesh.group_names.size(); ++g) {
          remap[g] = g;
          ObjectInfo info;
          info.name = mesh.group_names[g];
          scene.objects.push_back(info);
        }
      for (size_t t = 0; t < n; ++t) {
        uint32_t& id = remap[kept_group[t]];
        if (id == kNoObject) {
          id = static_cast<uint32_t>(scene.objects.size());
          ObjectInfo info;
          info.name = has_groups ? mesh.group_names[kept_group[t]] : "object";
          scene.objects.push_back(info);
        }
        scene.triangle_object[t] = id;
      }
      break;
    }
    case ObjectGrouping::kComponents: {
      const std::vector<uint32_t> welded = weld_positions(scene.vertices);
      UnionFind uf(scene.vertices.size());
      for (const auto& tri : scene.triangles) {
        uf.unite(welded[tri[0]], welded[tri[1]]);
        uf.unite(welded[tri[0]], welded[tri[2]]);
      }
      std::unordered_map<uint32_t, uint32_t> root_to_object;
      for (size_t t = 0; t < n; ++t) {
        const uint32_t root = uf.find(welded[scene.triangles[t][0]]);
        auto [it, inserted] = root_to_object.emplace(root, static_cast<uint32_t>(scene.objects.size()));
        if (inserted) {
          ObjectInfo info;
          info.name = "component_" + std::to_string(it->second);
          scene.objects.push_back(info);
        }
        scene.triangle_object[t] = it->second;
      }
      break;
    }
    case ObjectGrouping::kTriangles: {
      scene.objects.resize(n);
      for (size_t t = 0; t < n; ++t) {
        scene.triangle_object[t] = static_cast<uint32_t>(t);
        scene.objects[t].name = "triangle_" + std::to_string(t);
      }
      break;
    }
  }
  // An object is rendered (occludes) unless all of its triangles come from groups that are not
  // (do not).
  for (auto [flags, member] : {std::pair{&mesh.group_rendered, &ObjectInfo::rendered},
                               std::pair{&mesh.group_occluder, &ObjectInfo::occluder}}) {
    if (!has_groups || flags->empty()) continue;
    if (flags->size() != mesh.group_names.size()) throw Error(source, 0, "internal: group flags do not match the groups");
    for (ObjectInfo& o : scene.objects) o.*member = false;
    for (size_t t = 0; t < n; ++t)
      if ((*flags)[kept_group[t]]) scene.objects[scene.triangle_object[t]].*member = true;
  }
  if (mesh.keep_group_ids) {  // a kept id with no triangles draws nothing (and, with none, hides nothing)
    std::vector<uint8_t> has(scene.objects.size(), 0);
    for (uint32_t o : scene.triangle_object) has[o] = 1;
    for (size_t o = 0; o < scene.objects.size(); ++o)
      if (!has[o]) {
        scene.objects[o].rendered = false;
        scene.objects[o].occluder = true;  // not "seen through": it has nothing to see through
      }
  }
  scene.finalize();
  return scene;
}

void rotate_about_z(Scene& scene, double degrees, const Vec3& pivot) {
  const double r = degrees * M_PI / 180.0, c = std::cos(r), s = std::sin(r);
  for (Vec3& v : scene.vertices) {
    const Vec3 d = v - pivot;
    v = pivot + Vec3{c * d.x - s * d.y, s * d.x + c * d.y, d.z};
  }
  scene.finalize();
}

void translate(Scene& scene, const Vec3& offset) {
  for (Vec3& v : scene.vertices) v += offset;
  scene.finalize();
}

}  // namespace viewcells
