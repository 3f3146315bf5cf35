/// Our view cells against q3map2's clusters on a Quake 3 map: render cost, PVS agreement and
/// storage.
#include "viewcells/studies/q3map2.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/pvs/pvs.h"

namespace viewcells {

namespace {

uint64_t pair_key(int32_t cluster, uint32_t object) { return (uint64_t(uint32_t(cluster)) << 32) | object; }

/// Why segment i, seen from `cluster`, shows `object` although q3map2 does not admit it.
/// `far_plane` is the map's q3_far_plane().
std::string classify(const Q3Map& map, const Subdivision& q3, const SegmentSet& eval, size_t i, int32_t cluster,
                     uint32_t object, double far_plane) {
  // From the end that sees the object towards the other one.
  const bool at_a = eval.object_a[i] == object;
  const Vec3 p = at_a ? eval.a(i) : eval.b(i), q = at_a ? eval.b(i) : eval.a(i);
  const double len = length(q - p);
  if (!(len > 0)) return "crack";
  // Leave the surfaces at both ends alone: their hit points may round into the wall.
  const double d = std::min(1.0, 0.1 * len) / len;
  const Vec3 p1 = p + (q - p) * d, q1 = q + (p - q) * d;
  std::vector<std::tuple<int32_t, double, double>> pieces, stack;
  q3.pieces_of_segment(p1, q1, pieces, stack);
  // The solid piece nearest the object, if any: what made that space solid for q3map2?
  int32_t solid_leaf = -1;
  double t_mid = 0, t_first = 2;
  for (const auto& [n, t0, t1] : pieces) {
    const int32_t leaf = q3_leaf_of_node(map, n);
    if (map.leaves[leaf].cluster >= 0 || t0 >= t_first) continue;
    solid_leaf = leaf;
    t_first = t0;
    t_mid = 0.5 * (t0 + t1);
  }
  if (solid_leaf >= 0) {
    const Vec3 m = p1 + (q1 - p1) * t_mid;
    const Q3Leaf& leaf = map.leaves[solid_leaf];
    for (int32_t k = 0; k < leaf.brush_count; ++k) {
      const Q3Brush& b = map.brushes[map.leaf_brushes[leaf.first_brush + k]];
      if (!map.in_brush(b, m)) continue;
      // The sides where the segment enters and leaves the brush (clipping the line by it):
      // if the eye passes one that is not drawn, the brush is invisible from there.
      double t_in = -1, t_out = 2;
      int32_t side_in = -1, side_out = -1;
      for (int32_t j = 0; j < b.side_count; ++j) {
        const Q3Plane& pl = map.planes[map.brush_sides[b.first_side + j].plane];
        const double d0 = dot(pl.normal, p1) - pl.dist, d1 = dot(pl.normal, q1) - pl.dist;
        if (d0 == d1) continue;
        const double t = d0 / (d0 - d1);
        if (d0 > d1 && t > t_in) t_in = t, side_in = j;
        if (d0 < d1 && t < t_out) t_out = t, side_out = j;
      }
      bool undrawn = false;
      for (const auto& [t, j] : {std::pair{t_in, side_in}, std::pair{t_out, side_out}})
        if (j >= 0 && t > 0 && t < 1)
          undrawn |= (map.shaders[map.brush_sides[b.first_side + j].shader].surface_flags & kQ3SurfNodraw) != 0;
      return undrawn ? "invisible" : "crack";
    }
    return "void";
  }
  const int32_t seen_in = map.leaves[map.leaf_at(p1)].cluster;
  if (seen_in == cluster || map.cluster_sees(cluster, seen_in)) return "unlisted";
  // Farther from the cluster than the map's far plane: q3map2 culled it on purpose.
  if (far_plane > 0) {
    double nearest = 2;
    for (const auto& [n, t0, t1] : pieces)
      if (map.leaves[q3_leaf_of_node(map, n)].cluster == cluster) nearest = std::min(nearest, t0);
    if (nearest <= 1 && nearest * length(q1 - p1) > far_plane) return "far";
  }
  return "rejected";
}

}  // namespace

Q3Comparison compare_with_q3map2(const Scene& scene, const Q3Map& map, const RayCaster& caster, CompareConfig config) {
  if (!map.has_visibility()) throw Error(map.path, 0, "the map has no visibility data: nothing to compare with");
  if (std::find(config.methods.begin(), config.methods.end(), "av-m") == config.methods.end())
    throw Error("the comparison with q3map2 needs av-m among the methods");
  q3_object_surfaces(scene, map);  // other object groupings fail here, before any sampling
  Q3Comparison out;
  out.cluster_count = static_cast<uint32_t>(map.cluster_count);
  const Box3 box = config.construction.view_box.empty() ? q3_view_box(map) : config.construction.view_box;
  const auto inside = [&map](const Vec3& p) { return q3_in_view_space(map, p); };
  for (SamplerConfig* sc : {&config.construction, &config.evaluation}) {
    sc->view_box = box;
    sc->view_space = inside;
  }
  const Subdivision q3 = q3_subdivision(map, box);
  config.prepare = [&q3](Subdivision& s) { weight_by_view_space(s, q3); };
  if (config.max_cells == 0) config.max_cells = 3 * out.cluster_count;
  config.keep_models = true;
  out.ours = compare_methods(scene, caster, config);
  const SegmentSet& eval = out.ours.evaluation_segments;

  // q3map2's clusters on the same evaluation segments.
  const std::vector<std::vector<uint32_t>> q3_leaf_pvs = evaluation_pvs(q3, eval);
  out.clusters = q3_cluster_cells(scene, map, q3, q3_leaf_pvs, config.model);
  for (const MethodResult& m : out.ours.methods) {
    if (m.method != "av-m") continue;
    out.build_seconds = m.build_seconds;
    const auto& cells = m.evaluated.cells;
    out.avm_cost_at_clusters = std::binary_search(cells.begin(), cells.end(), out.cluster_count)
                                   ? m.evaluated.at(out.cluster_count)
                                   : std::numeric_limits<double>::quiet_NaN();
    for (size_t k = 0; k < cells.size() && !out.avm_cells_to_match; ++k)
      if (m.evaluated.cost[k] <= out.clusters.cost) out.avm_cells_to_match = cells[k];
  }

  // PVS agreement: what our evaluation samples see from each cluster against what q3map2 admits.
  const std::vector<std::vector<uint32_t>> admitted = q3_admitted_objects(scene, map);
  double ratio_sum = 0;
  size_t ratio_count = 0;
  std::unordered_map<uint64_t, size_t> witness;  // excluded pair -> first segment seeing it
  for (int32_t c = 0; c < map.cluster_count; ++c) {
    uint64_t seen = 0;
    for (uint32_t o : out.clusters.pvs[c]) {
      if (!scene.objects[o].rendered) continue;
      ++seen;
      if (!std::binary_search(admitted[c].begin(), admitted[c].end(), o))
        witness.emplace(pair_key(c, o), std::numeric_limits<size_t>::max());
    }
    out.ours_entries += seen;
    out.q3_entries += admitted[c].size();
    if (!admitted[c].empty()) {
      ratio_sum += static_cast<double>(seen) / static_cast<double>(admitted[c].size());
      ++ratio_count;
    }
  }
  out.mean_pvs_ratio = ratio_count ? ratio_sum / static_cast<double>(ratio_count) : 0.0;
  if (!witness.empty()) {
    // The first evaluation segment behind each excluded pair (the minimum: thread-count free).
    using Found = std::unordered_map<uint64_t, size_t>;
    tbb::enumerable_thread_specific<Found> found;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, eval.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      Found& f = found.local();
      std::vector<int32_t> leaves;
      std::vector<std::tuple<int32_t, double, double>> stack;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        leaves.clear();
        q3.leaves_of_segment(eval.a(i), eval.b(i), leaves, stack);
        for (int32_t n : leaves) {
          const int32_t c = map.leaves[q3_leaf_of_node(map, n)].cluster;
          if (c < 0) continue;
          for (uint32_t o : {eval.object_a[i], eval.object_b[i]}) {
            if (o == kNoObject || !witness.count(pair_key(c, o))) continue;
            auto [it, fresh] = f.emplace(pair_key(c, o), i);
            if (!fresh) it->second = std::min(it->second, i);
          }
        }
      }
    });
    for (const Found& f : found)
      for (const auto& [key, i] : f) witness[key] = std::min(witness[key], i);
    const double far_plane = q3_far_plane(map);
    for (const auto& [key, i] : witness) {
      Q3Excluded e;
      e.cluster = static_cast<int32_t>(key >> 32);
      e.object = static_cast<uint32_t>(key & 0xffffffffu);
      e.segment = i;
      if (i == std::numeric_limits<size_t>::max()) throw Error("internal: an excluded object without its segment");
      e.cause = classify(map, q3, eval, i, e.cluster, e.object, far_plane);
      ++out.excluded_by_cause[e.cause];
      out.excluded.push_back(std::move(e));
    }
    std::sort(out.excluded.begin(), out.excluded.end(), [](const Q3Excluded& x, const Q3Excluded& y) {
      return std::tie(x.cluster, x.object) < std::tie(y.cluster, y.object);
    });
  }

  // Storage at q3map2's cell count.
  out.q3_row_bytes = static_cast<uint64_t>(map.cluster_count) * static_cast<uint64_t>(map.cluster_bytes);
  out.q3_leaf_surface_bytes = 4 * static_cast<uint64_t>(map.leaf_surfaces.size());
  const Subdivision& s = *out.ours.av_s;
  const MergeHistory& h = *out.ours.av_m;
  const size_t n = std::clamp<size_t>(out.cluster_count, h.min_cells(), h.leaf_count);
  const PvsFile f = make_pvs_file(s, leaf_pvs(s, out.ours.construction_segments), h, extract_by_count(h, n).cells);
  out.ours_compressed_bytes = compact_pvs_bytes(f.pvs, static_cast<uint32_t>(scene.object_count()));
  for (uint32_t c = 0; c < f.pvs.cell_count; ++c)
    out.ours_rle_bytes += rle_row(f.pvs.cell_pvs(c), static_cast<uint32_t>(scene.object_count())).size();
  return out;
}

}  // namespace viewcells
