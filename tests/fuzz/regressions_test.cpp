// Every input the fuzzers once found a crash, hang or sanitizer report with (kept in
// data/fuzz/regressions/FORMAT/), replayed through the same entry functions: each must now end
// in success or a viewcells::Error. Run under scripts/sanitize.sh, the sanitizers check them too.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "fuzz/entries.h"

namespace viewcells::fuzz {
namespace {

TEST(FuzzRegressions, SavedFindingsEndInAnErrorOrSuccess) {
  const std::pair<const char*, void (*)(const uint8_t*, size_t)> formats[] = {
      {"obj", entry_obj}, {"ply", entry_ply},       {"off", entry_off}, {"stl", entry_stl},     {"bsp", entry_bsp},
      {"glb", entry_glb}, {"fbx", entry_fbx},
      {"vseg", entry_vseg}, {"vcells", entry_vcells}, {"pvs", entry_pvs}, {"runtime", entry_runtime},
      {"vagvs", entry_vagvs}, {"bake", entry_bake}};
  const std::filesystem::path root = std::filesystem::path(VIEWCELLS_DATA_DIR) / "fuzz" / "regressions";
  size_t replayed = 0;
  for (const auto& [format, entry] : formats) {
    if (!std::filesystem::is_directory(root / format)) continue;
    for (const auto& file : std::filesystem::directory_iterator(root / format)) {
      std::ifstream in(file.path(), std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      SCOPED_TRACE(file.path().string());
      EXPECT_NO_THROW(entry(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
      ++replayed;
    }
  }
  EXPECT_GT(replayed, 0u) << "no saved findings under " << root;
}

}  // namespace
}  // namespace viewcells::fuzz
