/// A Quake 3 map's non-solid space and its BSP as a Subdivision, so q3map2's clusters are scored as
/// our cells are.
#include "viewcells/q3/view_space.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "viewcells/core/error.h"

namespace viewcells {

bool q3_in_view_space(const Q3Map& map, const Vec3& p) {
  const Q3Leaf& leaf = map.leaves[map.leaf_at(p)];
  if (leaf.cluster < 0) return false;
  // Detail brushes fill parts of non-solid leaves: no eye is inside them either.
  for (int32_t k = 0; k < leaf.brush_count; ++k) {
    const Q3Brush& b = map.brushes[map.leaf_brushes[leaf.first_brush + k]];
    if (map.opaque_brush(b) && map.in_brush(b, p, 0.0)) return false;
  }
  return true;
}

Box3 q3_view_box(const Q3Map& map) {
  Box3 box;
  for (const Q3Leaf& l : map.leaves)
    if (l.cluster >= 0 && !l.bounds.empty()) box.extend(l.bounds);
  if (box.empty() || !(box.volume() > 0)) throw Error(map.path, 0, "Quake 3 BSP: the map has no non-solid leaves");
  return box;
}

namespace {

/// The part of `poly` inside `box` (empty when none).
ConvexPolyhedron clip_to_box(ConvexPolyhedron poly, const Box3& box) {
  for (int k = 0; k < 3 && !poly.empty(); ++k)
    for (int side = 0; side < 2 && !poly.empty(); ++side) {
      const Plane plane = Plane::axis_aligned(k, side ? box.hi[k] : box.lo[k]);
      if (auto parts = poly.split(plane, -1)) {
        poly = side ? parts->first : parts->second;  // below hi, above lo
      } else {
        const double at = poly.centroid()[k];
        if (side ? at > box.hi[k] : at < box.lo[k]) poly = ConvexPolyhedron();
      }
    }
  return poly;
}

}  // namespace

Box3 q3_cover_box(const Q3Map& map) {
  const Box3 stored = q3_view_box(map);
  Box3 around = stored;
  for (int k = 0; k < 3; ++k) {
    around.lo[k] -= 2;
    around.hi[k] += 2;
  }
  const Subdivision s = q3_subdivision(map, around);
  const size_t inner = map.nodes.size();
  Box3 out = stored;
  for (size_t l = 0; l < map.leaves.size(); ++l) {
    const Q3Leaf& leaf = map.leaves[l];
    if (leaf.cluster < 0 || leaf.bounds.empty() || s.cells[inner + l].empty()) continue;
    Box3 rounded = leaf.bounds;
    for (int k = 0; k < 3; ++k) {
      rounded.lo[k] -= 1;
      rounded.hi[k] += 1;
    }
    const ConvexPolyhedron part = clip_to_box(s.cells[inner + l], rounded);
    if (!part.empty()) out.extend(part.bounds());
  }
  return out;
}

namespace {

/// The Q3 plane as a Plane whose positive side is Q3's front (children[0]); `flipped` when it
/// is an axial plane with a negative normal, which is kept exact as the opposite axis plane.
Plane to_plane(const Q3Plane& q, bool& flipped) {
  flipped = false;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    if (q.normal[i] == 0 && q.normal[j] == 0 && std::abs(q.normal[k]) == 1) {
      flipped = q.normal[k] < 0;
      return Plane::axis_aligned(k, flipped ? -q.dist : q.dist);
    }
  }
  const Vec3 n = normalize(q.normal);
  Vec3 u, v;
  orthonormal_basis(n, u, v);
  const Vec3 a = n * (q.dist / length(q.normal));
  constexpr double kSpan = 1024;  // map units: keeps the defining points well apart
  return Plane::through(a, a + u * kSpan, a + v * kSpan);
}

}  // namespace

Subdivision q3_subdivision(const Q3Map& map, const Box3& box) {
  if (box.empty() || !(box.volume() > 0)) throw Error("the view box of a Quake 3 map needs a positive volume");
  Subdivision s;
  s.view_box = box;
  const ConvexPolyhedron whole = ConvexPolyhedron::box(box, 0);
  for (int k = 0; k < 3; ++k) {
    s.planes.push_back(Plane::axis_aligned(k, box.lo[k]));
    s.planes.push_back(Plane::axis_aligned(k, box.hi[k]));
  }
  std::vector<bool> flipped(map.planes.size());
  for (size_t i = 0; i < map.planes.size(); ++i) {
    bool f = false;
    s.planes.push_back(to_plane(map.planes[i], f));
    flipped[i] = f;
  }
  const int32_t inner = static_cast<int32_t>(map.nodes.size());
  const auto node_of = [&](int32_t child) { return child >= 0 ? child : inner + (-child - 1); };
  s.nodes.resize(map.nodes.size() + map.leaves.size());
  for (int32_t i = 0; i < inner; ++i) {
    const Q3Node& q = map.nodes[i];
    BspNode& b = s.nodes[i];
    b.plane = 6 + q.plane;
    // Our child[0] is the negative side; Q3's children[0] is the front.
    const int32_t front = node_of(q.children[0]), back = node_of(q.children[1]);
    b.child[0] = flipped[q.plane] ? front : back;
    b.child[1] = flipped[q.plane] ? back : front;
    for (int32_t c : b.child) {
      if (s.nodes[c].parent != -1 || c == 0) throw Error(map.path, 0, "Quake 3 BSP: the node tree is not a tree");
      s.nodes[c].parent = i;
    }
  }
  s.cells.resize(s.nodes.size());
  clip_to_leaves(s, whole, [&](int32_t n, const ConvexPolyhedron& part) { s.cells[n] = part; });
  // Volumes and weights bottom-up (iterative post-order: map nodes need not be in any order).
  std::vector<std::pair<int32_t, bool>> stack{{0, false}};
  while (!stack.empty()) {
    auto [n, expanded] = stack.back();
    stack.pop_back();
    BspNode& b = s.nodes[n];
    if (b.plane < 0) {
      b.volume = s.cells[n].empty() ? 0.0 : s.cells[n].volume();
      b.weight = map.leaves[n - inner].cluster >= 0 ? b.volume : 0.0;
    } else if (!expanded) {
      stack.emplace_back(n, true);
      stack.emplace_back(b.child[0], false);
      stack.emplace_back(b.child[1], false);
    } else {
      b.volume = s.nodes[b.child[0]].volume + s.nodes[b.child[1]].volume;
      b.weight = s.nodes[b.child[0]].weight + s.nodes[b.child[1]].weight;
    }
  }
  return s;
}

void keep_leaf_weights(Subdivision& q3, const Q3Map& map, const std::vector<bool>& keep) {
  if (keep.size() != map.leaves.size() || q3.nodes.size() != map.nodes.size() + map.leaves.size())
    throw Error("keep_leaf_weights: the leaves do not belong to this map's subdivision");
  const size_t inner = map.nodes.size();
  for (size_t l = 0; l < keep.size(); ++l)
    if (!keep[l]) q3.nodes[inner + l].weight = 0;
  // Inner nodes from their children (iterative post-order: map nodes need not be in any order).
  std::vector<std::pair<int32_t, bool>> stack{{0, false}};
  while (!stack.empty()) {
    auto [n, expanded] = stack.back();
    stack.pop_back();
    BspNode& b = q3.nodes[n];
    if (b.plane < 0) continue;
    if (!expanded) {
      stack.emplace_back(n, true);
      stack.emplace_back(b.child[0], false);
      stack.emplace_back(b.child[1], false);
    } else {
      b.weight = q3.nodes[b.child[0]].weight + q3.nodes[b.child[1]].weight;
    }
  }
}

double view_space_volume(const Subdivision& q3, const ConvexPolyhedron& cell) {
  if (cell.empty()) return 0.0;
  double v = 0;
  // Leaves of weight 0 are solid (or outside the box, where the cell has no volume either).
  clip_to_leaves(q3, cell, [&](int32_t n, const ConvexPolyhedron& part) {
    if (q3.nodes[n].weight > 0) v += part.volume();
  });
  return v;
}

void weight_by_view_space(Subdivision& s, const Subdivision& q3) {
  const std::vector<int32_t> leaves = s.leaves();
  if (s.cells.size() != s.nodes.size()) throw Error("weighting by the view space needs the cells' geometry");
  tbb::parallel_for(size_t{0}, leaves.size(), [&](size_t i) {
    const int32_t n = leaves[i];
    s.nodes[n].weight = view_space_volume(q3, s.cells[n]);
  });
  // Children have larger ids than their parents.
  for (size_t n = s.nodes.size(); n-- > 0;) {
    BspNode& b = s.nodes[n];
    if (b.plane >= 0) b.weight = s.nodes[b.child[0]].weight + s.nodes[b.child[1]].weight;
  }
  if (!(s.nodes[0].weight > 0)) throw Error("the view cells hold none of the map's non-solid space");
}

Q3ClusterCells q3_cluster_cells(const Scene& scene, const Q3Map& map, const Subdivision& q3,
                                const std::vector<std::vector<uint32_t>>& leaf_pvs, const CostModel& model) {
  if (!map.has_visibility()) throw Error(map.path, 0, "the map has no visibility data (no clusters to compare with)");
  if (leaf_pvs.size() != q3.nodes.size()) throw Error("leaf PVSs do not match the map's BSP");
  Q3ClusterCells out;
  const size_t nc = static_cast<size_t>(map.cluster_count);
  out.weight.assign(nc, 0.0);
  out.bounds.assign(nc, Box3{});
  out.pvs.assign(nc, {});
  out.pvs_cost.assign(nc, 0.0);
  const int32_t inner = static_cast<int32_t>(map.nodes.size());
  for (size_t l = 0; l < map.leaves.size(); ++l) {
    const int32_t c = map.leaves[l].cluster;
    if (c < 0) continue;
    if (c >= map.cluster_count) throw Error(map.path, 0, "Quake 3 BSP: leaf " + std::to_string(l) + " has cluster " +
                                                             std::to_string(c) + " of " + std::to_string(nc));
    const int32_t n = inner + static_cast<int32_t>(l);
    out.weight[c] += q3.nodes[n].weight;
    if (!q3.cells[n].empty()) out.bounds[c].extend(q3.cells[n].bounds());
    out.pvs[c] = unite_sorted(out.pvs[c], leaf_pvs[n]);
  }
  const std::vector<double> base = per_object_costs(scene, model);
  for (size_t c = 0; c < nc; ++c) {
    out.pvs_cost[c] = pvs_cost(scene, base, model, out.pvs[c], out.bounds[c]);
    out.total_weight += out.weight[c];
  }
  if (!(out.total_weight > 0)) throw Error(map.path, 0, "the clusters have no volume inside the view box");
  for (size_t c = 0; c < nc; ++c) out.cost += out.weight[c] * out.pvs_cost[c] / out.total_weight;
  return out;
}

std::vector<int32_t> q3_object_surfaces(const Scene& scene, const Q3Map& map) {
  std::vector<int32_t> out(scene.object_count(), -1);
  for (size_t o = 0; o < out.size(); ++o) {
    if (!scene.objects[o].rendered) continue;  // the solid brushes, or the sky
    const std::string& name = scene.objects[o].name;
    const size_t hash = name.rfind('#');
    char* end = nullptr;
    const long s = hash == std::string::npos ? -1 : std::strtol(name.c_str() + hash + 1, &end, 10);
    if (hash == std::string::npos || end == name.c_str() + hash + 1 || *end != '\0' || s < 0 ||
        s >= static_cast<long>(map.surfaces.size()))
      throw Error("object '" + name + "' is not one surface of " + map.path +
                  " (the comparison with q3map2 needs the map's surfaces as objects: --objects groups)");
    out[o] = static_cast<int32_t>(s);
  }
  return out;
}

std::vector<std::vector<uint32_t>> q3_admitted_objects(const Scene& scene, const Q3Map& map) {
  if (!map.has_visibility()) throw Error(map.path, 0, "the map has no visibility data");
  const std::vector<int32_t> surface = q3_object_surfaces(scene, map);
  std::vector<int32_t> object_of(map.surfaces.size(), -1);
  for (size_t o = 0; o < surface.size(); ++o)
    if (surface[o] >= 0) object_of[surface[o]] = static_cast<int32_t>(o);
  // The objects whose surfaces the leaves of each cluster list, as bit rows.
  const size_t nc = static_cast<size_t>(map.cluster_count), words = (scene.object_count() + 63) / 64;
  std::vector<uint64_t> touched(nc * words, 0);
  for (const Q3Leaf& l : map.leaves) {
    if (l.cluster < 0 || l.cluster >= map.cluster_count) continue;
    for (int32_t k = 0; k < l.surface_count; ++k) {
      const int32_t o = object_of[map.leaf_surfaces[l.first_surface + k]];
      if (o >= 0) touched[l.cluster * words + o / 64] |= uint64_t{1} << (o % 64);
    }
  }
  std::vector<std::vector<uint32_t>> out(nc);
  tbb::parallel_for(size_t{0}, nc, [&](size_t a) {
    std::vector<uint64_t> row(words, 0);
    for (size_t b = 0; b < nc; ++b)
      if (a == b || map.cluster_sees(static_cast<int32_t>(a), static_cast<int32_t>(b)))
        for (size_t w = 0; w < words; ++w) row[w] |= touched[b * words + w];
    for (size_t w = 0; w < words; ++w)
      for (uint64_t bits = row[w]; bits; bits &= bits - 1)
        out[a].push_back(static_cast<uint32_t>(w * 64 + __builtin_ctzll(bits)));
  });
  return out;
}

}  // namespace viewcells
