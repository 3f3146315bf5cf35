/// Path identity for output checks (core/paths.h).
#include "viewcells/core/paths.h"

namespace viewcells {

std::filesystem::path path_key(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path k = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal() : k;
}

bool inside_directory(const std::string& path, const std::string& dir) {
  const std::filesystem::path d = path_key(dir);
  for (std::filesystem::path p = path_key(path).parent_path(); !p.empty(); p = p.parent_path()) {
    if (p == d) return true;
    if (p == p.root_path()) break;
  }
  return false;
}

}  // namespace viewcells
