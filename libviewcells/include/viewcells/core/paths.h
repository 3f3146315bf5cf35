#pragma once
/// Whether two paths name the same file: what every front end asks before it writes (an output
/// must not replace an input, nor lie inside a work directory).
#include <filesystem>
#include <string>

namespace viewcells {

/// The path made absolute, with symbolic links and "..", "." resolved as far as the path
/// exists (the rest taken lexically): two paths of the same file give the same key.
std::filesystem::path path_key(const std::string& path);
/// Whether a and b name the same file (by path_key).
inline bool same_file(const std::string& a, const std::string& b) { return path_key(a) == path_key(b); }
/// Whether `path` lies inside the directory `dir` (at any depth).
bool inside_directory(const std::string& path, const std::string& dir);

}  // namespace viewcells
