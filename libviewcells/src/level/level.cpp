/// Level formats registered by front ends (level/level.h), and what a level brings by default.
#include "viewcells/level/level.h"

#include <map>
#include <mutex>

#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {

namespace {
std::mutex levels_mutex;
std::map<std::string, LevelFormat>& levels() {
  static std::map<std::string, LevelFormat> l;
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

void register_level_format(LevelFormat format) {
  if (format.extension.empty() || format.extension[0] != '.' || !format.read)
    throw Error("register_level_format: an extension with its dot and a reader are needed");
  const std::lock_guard<std::mutex> lock(levels_mutex);
  const std::string ext = format.extension;
  levels()[ext] = std::move(format);
}

bool is_level_file(const std::string& path) {
  const std::lock_guard<std::mutex> lock(levels_mutex);
  return levels().count(lower_extension(path)) > 0;
}

std::string level_format_name(const std::string& path) {
  const std::lock_guard<std::mutex> lock(levels_mutex);
  const auto it = levels().find(lower_extension(path));
  return it == levels().end() ? std::string() : it->second.name;
}

std::shared_ptr<const LevelData> read_level_data(const std::string& path) {
  std::function<std::shared_ptr<const LevelData>(const std::string&)> read;
  {
    const std::lock_guard<std::mutex> lock(levels_mutex);
    const auto it = levels().find(lower_extension(path));
    if (it == levels().end()) return nullptr;
    read = it->second.read;
  }
  return read(path);
}

}  // namespace viewcells
