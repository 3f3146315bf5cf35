#pragma once
// Checks of a glTF file's declared structure before Assimp reads it (gltf_check.cpp).
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace viewcells {

/// The deepest scene graph read (a malformed file can be cyclic or absurdly deep).
inline constexpr size_t kMaxNodeDepth = 256;

/// Throws Error naming `name` when the glTF (`binary`: GLB) in `bytes` declares sizes beyond
/// the bytes there are, or a node tree Assimp cannot take (deeper than 256, cyclic), or holds
/// non-finite numbers where Assimp would drop a mesh silently; external buffers are looked for
/// in `dir`.
void check_gltf(const std::string& name, const std::filesystem::path& dir, std::string_view bytes, bool binary);

}  // namespace viewcells
