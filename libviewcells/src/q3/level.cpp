/// A Quake 3 map as a level (q3/level.h), and the registration of its format.
#include "viewcells/q3/level.h"

#include <algorithm>
#include <mutex>
#include <nlohmann/json.hpp>

#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/q3/hidden.h"
#include "viewcells/q3/map_view_space.h"
#include "viewcells/q3/play.h"
#include "viewcells/q3/view_space.h"

namespace viewcells {

namespace {

class Q3Level final : public LevelData {
 public:
  explicit Q3Level(std::shared_ptr<const Q3Map> map) : map_(std::move(map)), view_space_(q3_map_view_space(map_)) {}
  const std::shared_ptr<const Q3Map>& map() const { return map_; }

  std::string kind() const override { return "Quake 3 map"; }
  std::shared_ptr<const ViewSpace> view_space() const override { return view_space_; }
  std::shared_ptr<const HiddenSpace> hidden_space(const Scene& scene, std::string& why) const override {
    why.clear();
    return q3_hidden_space(*map_, scene);
  }
  bool brings_pvs() const override { return true; }

  std::shared_ptr<const OwnPvs> own_pvs(const Scene& scene) const override {
    const Q3Map& map = *map_;
    if (!map.has_visibility())
      throw Error(map.path, 0, "the map has no visibility data: give a .pvs file to measure");
    auto out = std::make_shared<OwnPvs>();
    out->cells = q3_admitted_objects(scene, map);
    out->bytes = uint64_t(map.cluster_count) * uint64_t(map.cluster_bytes);
    out->extra_bytes = map.leaf_surfaces.size() * sizeof(int32_t);
    out->what = "the map's own PVS (q3map2's vis rows: " + std::to_string(map.cluster_count) +
                " clusters -> their leaves -> their surfaces)";
    const std::shared_ptr<const Q3Map> keep = map_;
    out->cell_at = [keep](const Vec3& p) { return keep->leaves[keep->leaf_at(p)].cluster; };
    // Why a frame shows an object q3map2's PVS leaves out: its surface is in no cluster's leaf
    // ("unlisted"), it lies beyond the map's far plane ("far"), or the PVS rejects the line of
    // sight ("rejected", or the models differ).
    const std::vector<int32_t> surface = q3_object_surfaces(scene, map);
    std::vector<bool> listed(map.surfaces.size(), false);
    for (const Q3Leaf& l : map.leaves)
      if (l.cluster >= 0)
        for (int32_t k = 0; k < l.surface_count; ++k) listed[map.leaf_surfaces[l.first_surface + k]] = true;
    std::vector<Box3> bounds;
    for (const ObjectInfo& o : scene.objects) bounds.push_back(o.bounds);
    const double far = q3_far_plane(map);
    out->cause = [surface, listed, bounds, far](uint32_t object, const Vec3& e) -> std::string {
      const Box3& b = bounds[object];
      const Vec3 nearest{std::clamp(e.x, b.lo.x, b.hi.x), std::clamp(e.y, b.lo.y, b.hi.y), std::clamp(e.z, b.lo.z, b.hi.z)};
      return !listed[surface[object]] ? "unlisted" : far > 0 && length(nearest - e) > far ? "far" : "rejected";
    };
    return out;
  }

  PlaySpaceComparison compare_play_space(const Scene& scene, const RayCaster& caster, const FloorSpace& found,
                                         double found_scale, uint64_t points, uint64_t seed,
                                         int image_width) const override {
    const PlaySpace play = q3_play_space(*map_, scene, caster, PlaySpaceConfig{});
    const PlaySpaceOverlap o =
        q3_play_space_overlap(*map_, scene, caster, play, found, found_scale, points, seed, image_width);
    PlaySpaceComparison c;
    c.reference_volume = o.map_volume;
    c.found_volume = o.found_volume;
    c.both_volume = o.both_volume;
    c.points = o.points;
    c.reference_rule = play.rule;
    c.width = o.width;
    c.height = o.height;
    c.rgb = o.rgb;
    return c;
  }

  std::vector<std::pair<std::string, std::string>> info_lines() const override {
    const Q3Map& map = *map_;
    const Q3MeshStats& st = mesh_stats();
    std::vector<std::pair<std::string, std::string>> out;
    out.emplace_back("quake 3 map", "IBSP version " + std::to_string(map.version) + ", " +
                                        std::to_string(map.shaders.size()) + " shaders, " +
                                        std::to_string(map.nodes.size()) + " nodes, " +
                                        std::to_string(map.leaves.size()) + " leaves (" +
                                        std::to_string(solid_leaves()) + " solid)");
    out.emplace_back("world surfaces", std::to_string(st.surfaces[0]) + " opaque, " + std::to_string(st.surfaces[1]) +
                                           " sky (they close the map for rays but are not rendered: no render cost), " +
                                           std::to_string(st.surfaces[2]) +
                                           " water/fog/translucent (rendered, seen through: they stop no ray), " +
                                           std::to_string(st.surfaces[3]) + " nodraw/hint/skip/flare (left out); " +
                                           std::to_string(st.patches) + " patches tessellated at level 4");
    out.emplace_back("solid brushes", std::to_string(st.brush_hulls) + " of " + std::to_string(map.world_brush_count) +
                                          " as hulls 0.5 units inside their sides (occlude, not rendered)");
    out.emplace_back("visibility", map.has_visibility() ? std::to_string(map.cluster_count) + " clusters, rows of " +
                                                              std::to_string(map.cluster_bytes) + " bytes (q3map2's PVS)"
                                                        : std::string("none (the map was not vis-compiled)"));
    out.emplace_back("spawn points", std::to_string(st.spawn_points));
    return out;
  }
  std::string info_key() const override { return "quake3"; }
  std::string info_json() const override {
    const Q3Map& map = *map_;
    const Q3MeshStats& st = mesh_stats();
    const nlohmann::json j = {
        {"version", map.version},
        {"leaves", map.leaves.size()},
        {"solid_leaves", solid_leaves()},
        {"surfaces", {{"opaque", st.surfaces[0]}, {"sky", st.surfaces[1]}, {"non_occluding", st.surfaces[2]},
                      {"skipped", st.surfaces[3]}, {"patches", st.patches}}},
        {"brush_hulls", st.brush_hulls},
        {"clusters", map.cluster_count},
        {"cluster_row_bytes", map.cluster_bytes},
        {"spawn_points", st.spawn_points}};
    return j.dump();
  }

 private:
  /// What the map's world mesh holds by kind: made once, when `info` first asks.
  const Q3MeshStats& mesh_stats() const {
    std::call_once(stats_once_, [this] { q3_world_mesh(*map_, {}, &stats_); });
    return stats_;
  }
  size_t solid_leaves() const {
    size_t n = 0;
    for (const Q3Leaf& l : map_->leaves) n += l.cluster < 0;
    return n;
  }
  std::shared_ptr<const Q3Map> map_;
  std::shared_ptr<const ViewSpace> view_space_;
  mutable std::once_flag stats_once_;
  mutable Q3MeshStats stats_;
};

}  // namespace

bool is_q3_map(const std::string& path) { return lower_extension(path) == ".bsp"; }

std::shared_ptr<const Q3Map> q3_map_of(const LevelData* level) {
  const auto* q = dynamic_cast<const Q3Level*>(level);
  return q ? q->map() : nullptr;
}

std::shared_ptr<const LevelData> q3_level(std::shared_ptr<const Q3Map> map) {
  return std::make_shared<const Q3Level>(std::move(map));
}

void register_q3_map_format() {
  register_scene_format({".bsp", "Quake 3 map", [](const std::string& path) {
                           RawMesh mesh = q3_world_mesh(read_q3bsp(path));
                           mesh.metres_per_unit = 1.0 / 32;  // its 56-unit player 1.75 m tall
                           return mesh;
                         }});
  register_level_format({".bsp", "Quake 3 map", [](const std::string& path) {
                           return q3_level(std::make_shared<const Q3Map>(read_q3bsp(path)));
                         }});
}

}  // namespace viewcells
