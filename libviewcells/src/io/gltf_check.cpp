// Checks of a glTF file's declared structure before Assimp reads it (gltf_check.h).
#include "gltf_check.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "viewcells/core/error.h"

namespace viewcells {

namespace {

// Assimp trusts the sizes a glTF file declares (a GLB's total length, a buffer's byteLength) and
// allocates them before reading: a 2 kB file that declares 2 GB makes it allocate 2 GB. So the
// declared sizes are checked against the bytes there are first, which bounds memory by the
// file's size.
class GltfCheck {
 public:
  GltfCheck(const std::string& name, const std::filesystem::path& dir) : name_(name), dir_(dir) {}

  void check(std::string_view bytes, bool binary) {
    std::string_view json_text = bytes;
    uint64_t bin_bytes = 0;
    bool has_bin = false;
    uint32_t glb_version = 0;
    if (binary) {
      if (bytes.size() < 20) fail("shorter than a GLB header");
      if (bytes.substr(0, 4) != "glTF") fail("not a binary glTF file (no 'glTF' magic)");
      glb_version = u32(bytes, 4);
      const uint32_t total = u32(bytes, 8), json_len = u32(bytes, 12);
      if (glb_version != 1 && glb_version != 2) fail("GLB version " + std::to_string(glb_version));
      if (total != bytes.size())
        fail("the GLB header declares " + std::to_string(total) + " bytes, the file has " +
             std::to_string(bytes.size()));
      if (json_len > bytes.size() - 20) fail("the JSON chunk runs past the end of the file");
      json_text = bytes.substr(20, json_len);
      if (glb_version == 2) {
        if (bytes.substr(16, 4) != std::string_view("JSON", 4)) fail("the first GLB chunk is not JSON");
        const uint64_t next = 20 + uint64_t{json_len};
        if (next + 8 <= bytes.size()) {
          const uint32_t bin_len = u32(bytes, next);
          if (bin_len > bytes.size() - next - 8) fail("the BIN chunk runs past the end of the file");
          has_bin = bytes.substr(next + 4, 4) == std::string_view("BIN\0", 4);
          bin_bytes = bin_len;
        }
      } else {  // glTF 1.0's binary body follows the JSON
        has_bin = true;
        bin_bytes = bytes.size() - 20 - json_len;
      }
    }
    nlohmann::json doc;
    try {
      doc = nlohmann::json::parse(json_text);
    } catch (const nlohmann::json::exception& e) {
      fail(std::string("its JSON does not parse: ") + e.what());
    }
    if (!doc.is_object()) fail("its JSON is not an object");
    // glTF 2.0 keeps these in arrays (referred to by index), glTF 1.0 in objects (by name).
    std::map<std::string, uint64_t> buffer_bytes, view_bytes;
    for_each(doc, "buffers", [&](const std::string& id, const nlohmann::json& b) {
      const uint64_t declared = size_of(b, "byteLength");
      uint64_t available = 0;
      if (id == "binary_glTF" || !b.contains("uri")) {  // the GLB's binary chunk (1.0: by name)
        if (!has_bin || buffer_bytes.count("glb")) fail("a buffer without a URI and no GLB BIN chunk for it");
        buffer_bytes["glb"] = 0;
        available = bin_bytes;
      } else if (!b["uri"].is_string()) {
        fail("a buffer's URI is not a string");
      } else {
        available = uri_bytes(b["uri"].get<std::string>());
      }
      if (declared > available)
        fail("a buffer declares " + std::to_string(declared) + " bytes and has " + std::to_string(available));
      buffer_bytes[id] = declared;
    });
    for_each(doc, "bufferViews", [&](const std::string& id, const nlohmann::json& v) {
      const uint64_t offset = size_of(v, "byteOffset"), length = size_of(v, "byteLength");
      const auto buffer = buffer_bytes.find(ref(v, "buffer"));
      if (buffer == buffer_bytes.end()) fail("a buffer view names a missing buffer");
      if (offset > buffer->second || length > buffer->second - offset)
        fail("a buffer view runs past the end of its buffer");
      view_bytes[id] = length;
    });
    for_each(doc, "accessors", [&](const std::string&, const nlohmann::json& a) {
      const uint64_t count = size_of(a, "count");
      if (count > (uint64_t{1} << 31)) fail("an accessor declares " + std::to_string(count) + " elements");
      if (!a.contains("bufferView")) return;  // all zeros (or sparse): sized by count alone
      const uint64_t offset = size_of(a, "byteOffset");
      const auto view = view_bytes.find(ref(a, "bufferView"));
      if (view == view_bytes.end()) fail("an accessor names a missing buffer view");
      // At least one byte per element must be there (the exact element size is Assimp's check).
      if (count > 0 && (offset >= view->second || count - 1 > view->second - offset))
        fail("an accessor declares more elements than its buffer view holds");
    });
    for_each(doc, "images", [&](const std::string&, const nlohmann::json& im) {
      if (im.is_object() && im.contains("uri") && im["uri"].is_string()) {
        const std::string uri = im["uri"].get<std::string>();
        if (uri.rfind("data:", 0) != 0) check_inside_folder(uri, "image");
      }
    });
    check_node_depth(doc);
  }

 private:
  [[noreturn]] void fail(const std::string& why) const { throw Error(name_, 0, "broken glTF: " + why); }

  /// Assimp walks the node tree recursively and overflows its stack on a chain some ten
  /// thousand deep: a valid file too deep (or cyclic) is refused here, by name, before it.
  void check_node_depth(const nlohmann::json& doc) const {
    std::map<std::string, std::vector<std::string>> children;
    for_each(doc, "nodes", [&](const std::string& id, const nlohmann::json& n) {
      auto& mine = children[id];
      if (!n.is_object() || !n.contains("children")) return;
      const auto& c = n["children"];
      if (!c.is_array()) fail("a node's children are not an array");
      for (const auto& child : c) {
        if (child.is_string()) mine.push_back(child.get<std::string>());
        else if (child.is_number_unsigned() || (child.is_number_integer() && child.get<int64_t>() >= 0))
          mine.push_back(std::to_string(child.get<uint64_t>()));
        else fail("a node's child is not a reference");
      }
    });
    // Longest path below each node, iteratively (post-order); a node met again on the path is a cycle.
    std::map<std::string, size_t> depth;
    std::map<std::string, bool> on_path;
    for (const auto& [root, unused] : children) {
      if (depth.count(root)) continue;
      std::vector<std::pair<std::string, size_t>> stack{{root, 0}};  // (node, next child)
      on_path[root] = true;
      while (!stack.empty()) {
        auto& [node, next] = stack.back();
        const auto it = children.find(node);
        if (it != children.end() && next < it->second.size()) {
          const std::string child = it->second[next++];
          if (on_path[child]) fail("the node tree has a cycle");
          if (!depth.count(child)) {
            on_path[child] = true;
            stack.push_back({child, 0});
          }
          continue;
        }
        size_t d = 1;
        if (it != children.end())
          for (const std::string& c : it->second) d = std::max(d, 1 + depth[c]);
        if (d > kMaxNodeDepth)  // a valid file, beyond what is read: not "broken"
          throw Error(name_, 0, "its node tree is " + std::to_string(d) + " or more nodes deep, more than the " +
                                    std::to_string(kMaxNodeDepth) + " levels viewcells reads (flatten the hierarchy)");
        depth[node] = d;
        on_path[node] = false;
        stack.pop_back();
      }
    }
  }

  static uint32_t u32(std::string_view b, uint64_t at) {
    uint32_t v = 0;
    std::memcpy(&v, b.data() + at, 4);
    return v;
  }

  /// Calls f(id, entry) for every entry of doc[key]: ids are indices (2.0) or names (1.0).
  template <class F>
  void for_each(const nlohmann::json& doc, const char* key, F&& f) const {
    if (!doc.contains(key)) return;
    const auto& c = doc[key];
    if (c.is_array()) {
      for (size_t i = 0; i < c.size(); ++i) f(std::to_string(i), c[i]);
    } else if (c.is_object()) {
      for (const auto& [id, entry] : c.items()) f(id, entry);
    } else {
      fail(std::string("'") + key + "' is neither an array nor an object");
    }
  }

  /// A reference to another entry: an index (2.0) or a name (1.0), as the id for_each gives.
  std::string ref(const nlohmann::json& o, const char* key) const {
    if (!o.contains(key)) fail(std::string("an entry lacks '") + key + "'");
    const auto& v = o[key];
    if (v.is_string()) return v.get<std::string>();
    if (v.is_number_unsigned() || (v.is_number_integer() && v.get<int64_t>() >= 0))
      return std::to_string(v.get<uint64_t>());
    fail(std::string("'") + key + "' is not a reference");
  }

  uint64_t size_of(const nlohmann::json& o, const char* key) const {
    if (!o.is_object()) fail("an entry is not an object");
    if (!o.contains(key)) return 0;
    const auto& v = o[key];
    if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
      fail(std::string("'") + key + "' is not a non-negative integer");
    return v.get<uint64_t>();
  }

  /// The bytes a buffer URI gives: a data URI's decoded length, or an external file's size.
  uint64_t uri_bytes(const std::string& uri) const {
    if (uri.rfind("data:", 0) == 0) {
      const size_t comma = uri.find(',');
      if (comma == std::string::npos) fail("a data URI without data");
      return (uri.size() - comma - 1) / 4 * 3 + 3;
    }
    check_inside_folder(uri, "buffer");
    std::error_code ec;
    const auto path = dir_ / uri;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) fail("its buffer file '" + uri + "' cannot be read");
    return size;
  }

  /// An external file a glTF names must be in its folder or below: a level from an untrusted
  /// source (a mod, an upload) may not read the baking machine's files ("../../etc/passwd", an
  /// absolute path, another scheme, or a symbolic link out). Checked as written and with its
  /// percent escapes decoded, as a reader may take it either way.
  void check_inside_folder(const std::string& uri, const char* what) const {
    namespace fs = std::filesystem;
    auto refuse = [&] {
      fail(std::string("its ") + what + " file '" + uri +
           "' is outside the file's folder: external files must be relative paths inside it");
    };
    if (uri.find("://") != std::string::npos || uri.rfind("file:", 0) == 0) refuse();
    std::string decoded;
    for (size_t i = 0; i < uri.size(); ++i) {
      if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
          std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
        decoded += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
        i += 2;
      } else {
        decoded += uri[i];
      }
    }
    std::error_code ec;
    const fs::path base = fs::weakly_canonical(fs::absolute(dir_.empty() ? fs::path(".") : dir_), ec);
    for (const std::string& u : {uri, decoded}) {
      if (u.empty() || u.front() == '/' || u.front() == '\\' || (u.size() > 1 && u[1] == ':')) refuse();
      const fs::path p = fs::weakly_canonical(base / u, ec);
      if (ec) refuse();
      const fs::path rel = p.lexically_relative(base);
      if (rel.empty() || *rel.begin() == "..") refuse();
    }
  }

  std::string name_;
  std::filesystem::path dir_;
};

}  // namespace

void check_gltf(const std::string& name, const std::filesystem::path& dir, std::string_view bytes, bool binary) {
  GltfCheck(name, dir).check(bytes, binary);
}

}  // namespace viewcells
