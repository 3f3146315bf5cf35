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
#include <cctype>
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
#include "gltf_check.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

// Guards against scene graphs that are cyclic or absurdly deep (a malformed file: kMaxNodeDepth,
// gltf_check.h), and against instancing that multiplies a small file into more geometry than
// any level holds.
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

/// Whether an empty node marks where players start: its name holds "spawn", "player start"
/// (or player_start, PlayerStart) or "info_player" (a Quake map's spawn entities), any case.
bool is_start_name(std::string name) {
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::erase_if(name, [](char c) { return c == ' ' || c == '_' || c == '-' || c == '.'; });
  return name.find("spawn") != std::string::npos || name.find("playerstart") != std::string::npos ||
         name.find("infoplayer") != std::string::npos;
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
    if (node->mNumMeshes == 0 && is_start_name(label)) {
      const Vec3 p{world.a4, world.b4, world.c4};  // the node's origin
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) mesh_.start_points.push_back(p);
    }
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
  put(&m.metres_per_unit, sizeof m.metres_per_unit);
  put_u64(m.start_points.size());
  put(m.start_points.data(), m.start_points.size() * sizeof(Vec3));
  return out;
}

RawMesh decode(const std::string& b, const std::string& name) {
  size_t pos = 0;
  auto get = [&](void* p, size_t n) {
    if (n > b.size() - pos) throw Error(name, 0, "internal: the Assimp reader's answer is truncated");
    if (n == 0) return;  // an empty vector's data() may be null, which memcpy may not be given
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
  get(&m.metres_per_unit, sizeof m.metres_per_unit);
  m.start_points.resize(get_u64());
  get(m.start_points.data(), m.start_points.size() * sizeof(Vec3));
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
    check_gltf(path, std::filesystem::path(path).parent_path(), bytes, bytes.rfind("glTF", 0) == 0);
  }
  CollectWarnings warnings;
  Assimp::Importer importer;
  configure(importer);
  const aiScene* scene = importer.ReadFile(path, kFlags);
  warnings.check(path);
  RawMesh m = convert(importer, scene, mode, path);
  if (is_gltf(ext)) m.metres_per_unit = 1;  // glTF 2.0, 3.4: units are metres
  return m;
}

static RawMesh read_assimp_bytes_here(std::string_view bytes, const std::string& extension, AssimpObjects mode,
                               const std::string& name) {
  if (bytes.empty()) throw Error(name, 0, "empty file");
  if (is_gltf(extension)) check_gltf(name, ".", bytes, bytes.substr(0, 4) == "glTF");
  CollectWarnings warnings;
  Assimp::Importer importer;
  configure(importer);
  const std::string hint = extension.empty() || extension[0] != '.' ? extension : extension.substr(1);
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kFlags, hint.c_str());
  warnings.check(name);
  RawMesh m = convert(importer, scene, mode, name);
  if (is_gltf(extension)) m.metres_per_unit = 1;  // glTF 2.0, 3.4: units are metres
  return m;
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
