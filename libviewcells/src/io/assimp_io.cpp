// Scenes through Assimp (glTF 2.0, FBX, COLLADA, 3DS and the other formats it reads well): the
// scene graph's nodes, transforms and instances become objects. Assimp stays inside this file.
#include <assimp/DefaultLogger.hpp>
#include <assimp/GltfMaterial.h>
#include <assimp/LogStream.hpp>
#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <map>
#include <mutex>
#include <unordered_map>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

// Guards against scene graphs that are cyclic or absurdly deep (a malformed file), and against
// instancing that multiplies a small file into more geometry than any level holds.
constexpr size_t kMaxNodeDepth = 256;
constexpr uint64_t kMaxInstancedTriangles = 200'000'000;

/// Assimp's message as printable text: its FBX reader quotes bytes of the file, which may be
/// binary; those are shown as \xNN, and a long message is cut.
std::string printable(const std::string& text) {
  std::string out;
  for (unsigned char ch : text) {
    if (out.size() > 300) {
      out += "...";
      break;
    }
    if (ch >= 0x20 && ch < 0x7f) {
      out += static_cast<char>(ch);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", ch);
      out += hex;
    }
  }
  return out;
}

/// True when a material lets one see through it: alpha-blended or alpha-tested in glTF, glTF's
/// transmission, or an opacity below one (FBX, COLLADA, 3DS, glTF's base colour alpha).
bool see_through_material(const aiMaterial* m) {
  if (!m) return false;
  float transmission = 0;
  if (m->Get(AI_MATKEY_TRANSMISSION_FACTOR, transmission) == AI_SUCCESS && transmission > 0) return true;
  aiString alpha_mode;
  if (m->Get(AI_MATKEY_GLTF_ALPHAMODE, alpha_mode) == AI_SUCCESS) {
    // glTF: the alpha mode decides; OPAQUE ignores the base colour's alpha (which Assimp
    // reports as the opacity).
    const std::string mode = alpha_mode.C_Str();
    return mode == "BLEND" || mode == "MASK";
  }
  float opacity = 1;
  if (m->Get(AI_MATKEY_OPACITY, opacity) == AI_SUCCESS && std::isfinite(opacity) && opacity < 0.999f) return true;
  return false;
}

/// Which axis is up in the file, as Assimp leaves it: glTF, COLLADA (converted by Assimp) and
/// most others are y-up; FBX says so in its metadata. Returns the rotation to viewcells' z-up.
aiMatrix4x4 to_z_up(const aiScene* scene) {
  int up = 1, sign = 1;
  if (scene->mMetaData) {
    int32_t v = 0;
    if (scene->mMetaData->Get("UpAxis", v) && v >= 0 && v <= 2) up = v;
    if (scene->mMetaData->Get("UpAxisSign", v) && (v == 1 || v == -1)) sign = v;
  }
  aiMatrix4x4 m;  // identity: z is up already
  if (up == 1) {  // (x, y, z) -> (x, -z, y)
    m = aiMatrix4x4(1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1);
  } else if (up == 0) {  // (x, y, z) -> (y, z, x)
    m = aiMatrix4x4(0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0, 0, 1);
  }
  if (sign == -1) {  // up is the negative axis: turn upside down about x
    m = aiMatrix4x4(1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1) * m;
  }
  return m;
}

class Builder {
 public:
  Builder(const aiScene* scene, AssimpObjects mode, const std::string& name) : scene_(scene), mode_(mode), name_(name) {}

  RawMesh build() {
    if (!scene_->mRootNode) throw Error(name_, 0, "the file has no scene graph (no root node)");
    visit(scene_->mRootNode, to_z_up(scene_), "", 0);
    return std::move(mesh_);
  }

 private:
  void visit(const aiNode* node, const aiMatrix4x4& parent, const std::string& parent_path, size_t depth) {
    if (depth > kMaxNodeDepth)
      throw Error(name_, 0, "the scene graph is deeper than " + std::to_string(kMaxNodeDepth) + " nodes (cyclic?)");
    const aiMatrix4x4 world = parent * node->mTransformation;
    std::string label = node->mName.length ? std::string(node->mName.C_Str()) : std::string();
    if (label.empty()) {
      label = parent_path;
      label.append(parent_path.empty() ? "node" : "/node");
    }
    const std::string node_name = unique(label);
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const unsigned mi = node->mMeshes[i];
      if (mi >= scene_->mNumMeshes) throw Error(name_, 0, "node '" + node_name + "' references a missing mesh");
      const aiMesh* mesh = scene_->mMeshes[mi];
      const aiMaterial* material =
          mesh->mMaterialIndex < scene_->mNumMaterials ? scene_->mMaterials[mesh->mMaterialIndex] : nullptr;
      const bool see_through = see_through_material(material);
      std::string object = node_name;
      if (mode_ == AssimpObjects::kMeshes) {
        const std::string mesh_name = mesh->mName.length ? mesh->mName.C_Str() : "mesh" + std::to_string(mi);
        object += '/';
        object += mesh_name;
        if (node->mNumMeshes > 1) object += '#' + std::to_string(i);
      } else if (see_through) {
        object += " (see-through)";  // a node's opaque and see-through meshes are two objects
      }
      add_mesh(mesh, world, group_of(object, see_through));
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) visit(node->mChildren[c], world, node_name, depth + 1);
  }

  std::string unique(const std::string& label) {
    const size_t n = ++name_uses_[label];
    return n == 1 ? label : label + "#" + std::to_string(n);
  }

  uint32_t group_of(const std::string& object, bool see_through) {
    auto [it, inserted] = groups_.emplace(object, static_cast<uint32_t>(mesh_.group_names.size()));
    if (inserted) {
      mesh_.group_names.push_back(object);
      mesh_.group_occluder.push_back(see_through ? 0 : 1);
    }
    return it->second;
  }

  void add_mesh(const aiMesh* mesh, const aiMatrix4x4& world, uint32_t group) {
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || !mesh->mVertices) return;
    triangles_ += mesh->mNumFaces;
    if (triangles_ > kMaxInstancedTriangles)
      throw Error(name_, 0, "the scene graph instances more than " + std::to_string(kMaxInstancedTriangles) +
                                " triangles");
    const uint32_t base = static_cast<uint32_t>(mesh_.vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      // In double: a level's large offsets survive the transform better than in float.
      const double x = p.x, y = p.y, z = p.z;
      const Vec3 q{world.a1 * x + world.a2 * y + world.a3 * z + world.a4,
                   world.b1 * x + world.b2 * y + world.b3 * z + world.b4,
                   world.c1 * x + world.c2 * y + world.c3 * z + world.c4};
      // As the OBJ reader: a NaN or infinite coordinate (in the file or after the node's
      // transform) is an error, never a mesh dropped without a word.
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
        throw Error(name_, 0, "mesh '" + std::string(mesh->mName.C_Str()) + "' has a vertex (" + std::to_string(v) +
                                  ") whose coordinates are not finite" +
                                  (std::isfinite(x) && std::isfinite(y) && std::isfinite(z) ? " after its node's transform" : ""));
      mesh_.vertices.push_back(q);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines: nothing that occludes or is drawn as a surface
      std::array<uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          throw Error(name_, 0, "mesh '" + std::string(mesh->mName.C_Str()) + "' has a face index out of range");
        tri[k] = base + face.mIndices[k];
      }
      mesh_.triangles.push_back(tri);
      mesh_.triangle_group.push_back(group);
    }
  }

  const aiScene* scene_;
  AssimpObjects mode_;
  std::string name_;
  RawMesh mesh_;
  std::unordered_map<std::string, size_t> name_uses_;
  std::map<std::string, uint32_t> groups_;
  uint64_t triangles_ = 0;
};

// Assimp repairs some broken input with only a warning (faces with out-of-range indices are
// dropped). Our readers reject such files, so its warnings are collected during a read and those
// that report lost data become errors. Assimp's logger is global; the collector is per thread.
thread_local std::vector<std::string>* t_warnings = nullptr;

class WarningCollector : public Assimp::LogStream {
 public:
  void write(const char* message) override {
    if (t_warnings && t_warnings->size() < 100) t_warnings->emplace_back(message);
  }
};

void install_logger() {
  static std::once_flag once;
  std::call_once(once, [] {
    Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);
    Assimp::DefaultLogger::get()->attachStream(new WarningCollector, Assimp::Logger::Warn | Assimp::Logger::Err);
  });
}

class CollectWarnings {
 public:
  CollectWarnings() { install_logger(), t_warnings = &warnings; }
  ~CollectWarnings() { t_warnings = nullptr; }
  /// Throws when Assimp said it dropped or could not use part of the file.
  void check(const std::string& name) const {
    for (const std::string& w : warnings) {
      if (w.find("out-of-range indices") != std::string::npos || w.find("dropped") != std::string::npos) {
        std::string text = w;
        while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
        if (const size_t colon = text.find(": "); colon != std::string::npos && colon < 12) text = text.substr(colon + 2);
        throw Error(name, 0, "broken scene data (Assimp: " + printable(text) + ")");
      }
    }
  }
  std::vector<std::string> warnings;
};

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
    std::error_code ec;
    const auto path = dir_ / uri;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) fail("its buffer file '" + uri + "' cannot be read");
    return size;
  }

  std::string name_;
  std::filesystem::path dir_;
};

// Assimp crashes on some malformed files (the fuzzer found a null dereference in its glTF 2.0
// importer). So it reads in a child process: a crash there is an Error here, never ours. The
// child sends the mesh (or its Error's message) back through a pipe.
void write_all(int fd, const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<size_t>(n);
  }
}

std::string encode(const RawMesh& m) {
  std::string out;
  auto put = [&](const void* p, size_t n) { out.append(static_cast<const char*>(p), n); };
  auto put_u64 = [&](uint64_t v) { put(&v, sizeof v); };
  put_u64(m.vertices.size());
  put(m.vertices.data(), m.vertices.size() * sizeof(Vec3));
  put_u64(m.triangles.size());
  put(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
  put(m.triangle_group.data(), m.triangle_group.size() * sizeof(uint32_t));
  put_u64(m.group_names.size());
  for (const std::string& g : m.group_names) {
    put_u64(g.size());
    put(g.data(), g.size());
  }
  put(m.group_occluder.data(), m.group_occluder.size());
  return out;
}

RawMesh decode(const std::string& b, const std::string& name) {
  size_t pos = 0;
  auto get = [&](void* p, size_t n) {
    if (n > b.size() - pos) throw Error(name, 0, "internal: the Assimp reader's answer is truncated");
    std::memcpy(p, b.data() + pos, n);
    pos += n;
  };
  auto get_u64 = [&] {
    uint64_t v = 0;
    get(&v, sizeof v);
    if (v > b.size()) throw Error(name, 0, "internal: the Assimp reader's answer is malformed");
    return v;
  };
  RawMesh m;
  m.vertices.resize(get_u64());
  get(m.vertices.data(), m.vertices.size() * sizeof(Vec3));
  m.triangles.resize(get_u64());
  get(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
  m.triangle_group.resize(m.triangles.size());
  get(m.triangle_group.data(), m.triangle_group.size() * sizeof(uint32_t));
  m.group_names.resize(get_u64());
  for (std::string& g : m.group_names) {
    g.resize(get_u64());
    get(g.data(), g.size());
  }
  m.group_occluder.resize(m.group_names.size());
  get(m.group_occluder.data(), m.group_occluder.size());
  return m;
}

template <class F>
RawMesh read_isolated(const std::string& name, F&& read) {
  int fds[2];
  if (pipe(fds) != 0) throw Error(name, 0, "cannot create a pipe for the Assimp reader");
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]), close(fds[1]);
    throw Error(name, 0, "cannot fork the Assimp reader");
  }
  if (pid == 0) {  // the child: read, answer, leave without running the parent's exit handlers
    close(fds[0]);
    std::string answer;
    try {
      answer = "M" + encode(read());
    } catch (const std::exception& e) {
      answer = std::string("E") + e.what();
    } catch (...) {  // the child must never return into the caller's code
      answer = "E" + name + ": the Assimp reader failed";
    }
    write_all(fds[1], answer);
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string answer;
  char buf[1 << 16];
  while (true) {
    const ssize_t n = ::read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    answer.append(buf, static_cast<size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status))
    throw Error(name, 0, "Assimp crashed reading it (signal " + std::to_string(WTERMSIG(status)) +
                             "): the file is malformed");
  // A child that exits without an answer and with a failing status crashed too (a sanitizer
  // reports a crash and exits rather than dying of the signal).
  if (answer.empty() && WIFEXITED(status) && WEXITSTATUS(status) != 0)
    throw Error(name, 0, "Assimp crashed reading it (exit status " + std::to_string(WEXITSTATUS(status)) +
                             "): the file is malformed");
  if (answer.empty()) throw Error(name, 0, "the Assimp reader ended without an answer");
  if (answer[0] == 'E') throw Error(answer.substr(1));  // already names the file
  return decode(answer.substr(1), name);
}

bool is_gltf(const std::string& ext) { return ext == ".gltf" || ext == ".glb"; }


constexpr unsigned kFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                            aiProcess_ValidateDataStructure;

RawMesh convert(Assimp::Importer& importer, const aiScene* scene, AssimpObjects mode, const std::string& name) {
  if (!scene) {
    std::string why = printable(importer.GetErrorString());
    if (why.empty()) why = "Assimp could not read it";
    // Point and line meshes are removed on reading (they draw no surface and hide nothing).
    if (why.find("No meshes remaining") != std::string::npos)
      throw Error(name, 0, "the file holds no triangles (only points or lines, or no meshes)");
    throw Error(name, 0, "not a readable scene: " + why);
  }
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) throw Error(name, 0, "the file holds no meshes (incomplete scene)");
  return Builder(scene, mode, name).build();
}

void configure(Assimp::Importer& importer) {
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
}

}  // namespace

bool is_assimp_extension(const std::string& ext) {
  static const char* const kExtensions[] = {".gltf", ".glb", ".fbx", ".dae", ".3ds", ".x", ".ase", ".lwo", ".ms3d"};
  return std::any_of(std::begin(kExtensions), std::end(kExtensions), [&](const char* e) { return ext == e; });
}

static RawMesh read_assimp_here(const std::string& path, AssimpObjects mode) {
  const std::string ext = lower_extension(path);
  if (is_gltf(ext)) {
    const std::string bytes = read_file_bytes(path);
    // A .gltf may be binary and a .glb text: the magic decides, as for Assimp.
    GltfCheck(path, std::filesystem::path(path).parent_path()).check(bytes, bytes.rfind("glTF", 0) == 0);
  }
  CollectWarnings warnings;
  Assimp::Importer importer;
  configure(importer);
  const aiScene* scene = importer.ReadFile(path, kFlags);
  warnings.check(path);
  return convert(importer, scene, mode, path);
}

static RawMesh read_assimp_bytes_here(std::string_view bytes, const std::string& extension, AssimpObjects mode,
                               const std::string& name) {
  if (bytes.empty()) throw Error(name, 0, "empty file");
  if (is_gltf(extension)) GltfCheck(name, ".").check(bytes, bytes.substr(0, 4) == "glTF");
  CollectWarnings warnings;
  Assimp::Importer importer;
  configure(importer);
  const std::string hint = extension.empty() || extension[0] != '.' ? extension : extension.substr(1);
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kFlags, hint.c_str());
  warnings.check(name);
  return convert(importer, scene, mode, name);
}

}  // namespace viewcells

namespace viewcells {

RawMesh read_assimp(const std::string& path, AssimpObjects mode) {
  return read_isolated(path, [&] { return read_assimp_here(path, mode); });
}

RawMesh read_assimp_bytes(std::string_view bytes, const std::string& extension, AssimpObjects mode,
                          const std::string& name) {
  return read_isolated(name, [&] { return read_assimp_bytes_here(bytes, extension, mode, name); });
}

}  // namespace viewcells
