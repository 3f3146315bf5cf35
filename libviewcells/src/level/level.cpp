/// Level formats registered by front ends (level/level.h), and what a level brings by default.
#include "viewcells/level/level.h"


#include "viewcells/core/error.h"
#include "viewcells/core/registry.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {

namespace {
ExtensionRegistry<LevelFormat>& levels() {
  static ExtensionRegistry<LevelFormat> l;
  return l;
}
}  // namespace

std::shared_ptr<const HiddenSpace> LevelData::hidden_space(const Scene&, std::string& why) const {
  why = "a " + kind() + " that proves nothing hidden";
  return nullptr;
}

std::shared_ptr<const OwnPvs> LevelData::own_pvs(const Scene&) const {
  throw Error("a " + kind() + " brings no PVS of its own: give a .pvs file to measure");
}

PlaySpaceComparison LevelData::compare_play_space(const Scene&, const RayCaster&, const FloorSpace&, double, uint64_t,
                                                  uint64_t, int) const {
  throw Error("a " + kind() + " knows no play space of its own to compare with");
}

void register_level_format(LevelFormat format) { levels().add(std::move(format), "register_level_format"); }

bool is_level_file(const std::string& path) { return levels().find(lower_extension(path)).has_value(); }

std::string level_format_name(const std::string& path) {
  const std::optional<LevelFormat> format = levels().find(lower_extension(path));
  return format ? format->name : std::string();
}

std::shared_ptr<const LevelData> read_level_data(const std::string& path) {
  const std::optional<LevelFormat> format = levels().find(lower_extension(path));
  return format ? format->read(path) : nullptr;
}

}  // namespace viewcells
