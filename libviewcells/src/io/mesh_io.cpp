// PLY, OFF and STL through OpenMesh's readers, feeding a raw-triangle importer: OpenMesh's own
// mesh kernels reject non-manifold faces (silently dropping geometry), which a visibility tool
// must not do. Also the extension dispatch of load_scene.
#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "viewcells/core/error.h"
#include "viewcells/io/q3bsp.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

/// Collects vertices and fan-triangulated faces; ignores every attribute.
class RawImporter : public OpenMesh::IO::BaseImporter {
 public:
  RawMesh mesh;
  size_t faces_read = 0;  ///< polygons, before triangulation

  VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    return add_vertex(OpenMesh::Vec3d(p[0], p[1], p[2]));
  }
  VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
    mesh.vertices.push_back({p[0], p[1], p[2]});
    return VertexHandle(static_cast<int>(mesh.vertices.size() - 1));
  }
  VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3d(0, 0, 0)); }
  void set_point(VertexHandle vh, const OpenMesh::Vec3f& p) override {
    if (vh.is_valid() && static_cast<size_t>(vh.idx()) < mesh.vertices.size())
      mesh.vertices[vh.idx()] = {p[0], p[1], p[2]};
  }
  FaceHandle add_face(const VHandles& idx) override {
    ++faces_read;
    if (idx.size() < 3) return FaceHandle();
    for (size_t i = 1; i + 1 < idx.size(); ++i)
      mesh.triangles.push_back({static_cast<uint32_t>(idx[0].idx()), static_cast<uint32_t>(idx[i].idx()),
                                static_cast<uint32_t>(idx[i + 1].idx())});
    return FaceHandle(static_cast<int>(mesh.triangles.size() - 1));
  }
  size_t n_vertices() const override { return mesh.vertices.size(); }
  size_t n_faces() const override { return mesh.triangles.size(); }
  size_t n_edges() const override { return 0; }
  bool is_triangle_mesh() const override { return false; }

  // Attributes we do not use.
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
  FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_halfedge(VertexHandle, HalfedgeHandle) override {}
  void set_normal(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(VertexHandle, const OpenMesh::Vec3d&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_color(VertexHandle, const OpenMesh::Vec4f&) override {}
  void set_texcoord(VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(HalfedgeHandle, HalfedgeHandle) override {}
  void set_face(HalfedgeHandle, FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_status(EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(FaceHandle, const OpenMesh::Vec4f&) override {}
  void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}
};

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// For text files: the first line holding a NaN or infinite number, or 0. OpenMesh's readers
/// do not report positions, so this gives the user a line to look at.
long find_non_finite_line(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.size() > 4096) return 0;  // binary data, not text
    std::string low(line.size(), ' ');
    std::transform(line.begin(), line.end(), low.begin(), [](unsigned char c) { return std::tolower(c); });
    for (const char* word : {"nan", "inf"}) {
      for (size_t p = low.find(word); p != std::string::npos; p = low.find(word, p + 1)) {
        const bool start_ok = p == 0 || std::isspace(static_cast<unsigned char>(low[p - 1])) ||
                              low[p - 1] == '-' || low[p - 1] == '+';
        if (start_ok) return line_no;
      }
    }
  }
  return 0;
}

/// OpenMesh's readers run past the end of a truncated file and invent geometry; compare what
/// was read with what the file declares (OFF and PLY headers, binary STL size, ASCII STL end).
void check_declared_counts(const std::string& path, const std::string& ext, const RawImporter& im) {
  std::ifstream in(path, std::ios::binary);
  std::string first;
  std::getline(in, first);
  auto mismatch = [&](uint64_t nv, uint64_t nf) {
    if (nv != im.mesh.vertices.size() || nf != im.faces_read)
      throw Error(path, 0, "truncated or malformed: the header declares " + std::to_string(nv) + " vertices and " +
                               std::to_string(nf) + " faces, the file holds " + std::to_string(im.mesh.vertices.size()) +
                               " and " + std::to_string(im.faces_read));
  };
  if (ext == ".off") {
    std::string line;
    uint64_t nv = 0, nf = 0;
    std::istringstream head(first);
    std::string magic;
    head >> magic;
    if (!(head >> nv >> nf)) {  // counts on the next non-comment line
      while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream counts(line);
        if (!(counts >> nv >> nf)) throw Error(path, 2, "OFF header lacks vertex and face counts");
        break;
      }
    }
    mismatch(nv, nf);
  } else if (ext == ".ply") {
    std::string line;
    uint64_t nv = 0, nf = 0;
    while (std::getline(in, line) && line.rfind("end_header", 0) != 0) {
      std::istringstream ls(line);
      std::string word, element;
      uint64_t n = 0;
      if (ls >> word >> element >> n && word == "element") {
        if (element == "vertex") nv = n;
        if (element == "face") nf = n;
      }
    }
    mismatch(nv, nf);
  } else if (ext == ".stl") {
    in.seekg(0, std::ios::end);
    const uint64_t size = static_cast<uint64_t>(in.tellg());
    const bool ascii = first.rfind("solid", 0) == 0 && im.faces_read > 0 &&
                       size != 84 + 50 * static_cast<uint64_t>(im.faces_read);
    if (ascii) {
      // A complete ASCII STL ends with "endsolid".
      in.seekg(size > 256 ? size - 256 : 0);
      std::string tail((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (tail.find("endsolid") == std::string::npos) throw Error(path, 0, "truncated ASCII STL (no endsolid)");
    } else {
      uint32_t declared = 0;
      in.seekg(80);
      in.read(reinterpret_cast<char*>(&declared), 4);
      if (!in || size != 84 + 50 * static_cast<uint64_t>(declared))
        throw Error(path, 0, "truncated binary STL: " + std::to_string(declared) + " triangles declared, " +
                                 std::to_string(size) + " bytes found");
    }
  }
}

RawMesh read_with_openmesh(const std::string& path) {
  static std::mutex mutex;  // OpenMesh's IOManager and log streams are process-global
  std::lock_guard lock(mutex);
  if (const long line = find_non_finite_line(path); line > 0)
    throw Error(path, line, "NaN or infinite coordinate");
  RawImporter importer;
  OpenMesh::IO::Options options;
  omerr().disable();
  omlog().disable();
  const bool ok = OpenMesh::IO::IOManager().read(path, importer, options);
  omerr().enable();
  if (!ok) throw Error(path, 0, "could not parse as " + lower_extension(path).substr(1) + " (malformed or truncated)");
  check_declared_counts(path, lower_extension(path), importer);
  return std::move(importer.mesh);
}

}  // namespace

Scene load_scene(const std::string& path, ObjectGrouping grouping) {
  if (!std::filesystem::exists(path)) throw Error(path, 0, "no such file");
  if (std::filesystem::is_directory(path)) throw Error(path, 0, "is a directory, not a scene file");
  const std::string ext = lower_extension(path);
  RawMesh mesh;
  if (ext == ".obj") {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path, 0, "cannot open file");
    mesh = read_obj(in, path);
  } else if (ext == ".ply" || ext == ".off" || ext == ".stl") {
    mesh = read_with_openmesh(path);
  } else if (ext == ".bsp") {
    // Quake 3 maps: the world's opaque surfaces, the sky and the solid brushes that close it
    // (neither rendered), patches at level 4.
    mesh = q3_world_mesh(read_q3bsp(path));
  } else {
    throw Error(path, 0, "unknown scene format '" + ext + "' (expected .obj, .ply, .off, .stl or .bsp)");
  }
  Scene scene = make_scene(std::move(mesh), grouping, path);
  if (scene.triangles.empty())
    throw Error(path, 0, scene.degenerate_dropped
                             ? "all " + std::to_string(scene.degenerate_dropped) + " triangles are degenerate"
                             : "the scene has no triangles");
  return scene;
}

}  // namespace viewcells
