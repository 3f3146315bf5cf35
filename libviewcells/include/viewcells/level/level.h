#pragma once
/// What a level file brings besides its triangles (a map compiler's BSP and PVS), from the
/// adapter of its format, which a front end registers (a Quake 3 map's: q3/level.h,
/// register_q3_map_format()). The pipeline asks this interface only, never the format: a second
/// format is a new adapter, not a change to the pipeline.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "viewcells/hidden/hidden_space.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/scene.h"
#include "viewcells/viewspace/floor_space.h"
#include "viewcells/viewspace/view_space.h"

namespace viewcells {

/// A PVS a level brings (a map compiler's), measured as a .pvs is.
struct OwnPvs {
  std::vector<std::vector<uint32_t>> cells;     ///< per cell, its visible objects, sorted
  std::function<int32_t(const Vec3&)> cell_at;  ///< the cell of a point, -1 in none (thread-safe)
  uint64_t bytes = 0;        ///< what it stores (a map's cluster rows)
  uint64_t extra_bytes = 0;  ///< what a renderer needs besides to use it (a map's leaf surface lists)
  std::string what;          ///< in words, for reports
  /// Why a frame shows an object this PVS leaves out, a word for reports ("unlisted", "far",
  /// "rejected").
  std::function<std::string(uint32_t object, const Vec3& eye)> cause;
};

/// The play space found from a level's floors against the level's own (play-space --map).
struct PlaySpaceComparison {
  double reference_volume = 0, found_volume = 0, both_volume = 0;  ///< in the level's units^3
  uint64_t points = 0;
  std::string reference_rule;
  double coverage() const { return reference_volume > 0 ? both_volume / reference_volume : 0; }
  double excess() const { return reference_volume > 0 ? (found_volume - both_volume) / reference_volume : 0; }
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  ///< top down: green both, red only the level's, blue only the found
};

class LevelData {
 public:
  virtual ~LevelData() = default;
  /// The format, for messages ("Quake 3 map").
  virtual std::string kind() const = 0;
  /// Where viewpoints can be, as the level knows it (a map's non-solid leaves, whose play space
  /// it knows too); null: the scene's default (its box, the play space from its floors).
  virtual std::shared_ptr<const ViewSpace> view_space() const { return nullptr; }
  /// What its solid space proves hidden; null, with the reason in `why`.
  virtual std::shared_ptr<const HiddenSpace> hidden_space(const Scene& scene, std::string& why) const;
  /// The PVS it brings, for `scene` (its triangles as loaded); Error saying why when it has none.
  virtual std::shared_ptr<const OwnPvs> own_pvs(const Scene& scene) const;
  /// Whether it brings a PVS at all (own_pvs may still fail: a map not vis-compiled).
  virtual bool brings_pvs() const { return false; }
  /// Its play space against one found from floors (`found`, whose units are `found_scale` times
  /// the level's); Error when it knows none.
  virtual PlaySpaceComparison compare_play_space(const Scene& scene, const RayCaster& caster, const FloorSpace& found,
                                                 double found_scale, uint64_t points, uint64_t seed,
                                                 int image_width) const;
  /// What `viewcells info` says of it: lines (label, text) for people, and the report's key
  /// and JSON object.
  virtual std::vector<std::pair<std::string, std::string>> info_lines() const { return {}; }
  virtual std::string info_key() const { return "level"; }
  virtual std::string info_json() const { return "{}"; }
};

/// A level format: its files' extension and how to read what they bring (the triangles come
/// from the scene reader registered with it, io/scene_io.h).
struct LevelFormat {
  std::string extension;  ///< ".bsp"
  std::string name;       ///< "Quake 3 map"
  std::function<std::shared_ptr<const LevelData>(const std::string& path)> read;
};
/// Registers `format` (again: replaces the one of the same extension). Thread-safe.
void register_level_format(LevelFormat format);
/// Whether `path`'s extension is a registered level format.
bool is_level_file(const std::string& path);
/// The registered level format's name for `path` ("Quake 3 map"), without reading it; "" when none.
std::string level_format_name(const std::string& path);
/// What the level file at `path` brings (read now), or null when its format is not a level's.
std::shared_ptr<const LevelData> read_level_data(const std::string& path);

}  // namespace viewcells
