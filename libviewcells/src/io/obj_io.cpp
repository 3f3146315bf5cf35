// OBJ reading and writing. The reader is our own (not OpenMesh's) because it must keep `o`/`g`
// groups as objects and report the line of every error.
#include <algorithm>
#include <filesystem>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include "viewcells/core/error.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::string_view next_token(std::string_view& rest) {
  size_t i = 0;
  while (i < rest.size() && is_space(rest[i])) ++i;
  size_t j = i;
  while (j < rest.size() && !is_space(rest[j])) ++j;
  std::string_view tok = rest.substr(i, j - i);
  rest.remove_prefix(j);
  return tok;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

/// Calls f(line_no, line) for every line of `text` with its comment removed, after checking
/// that it holds no binary data (an error naming `name`, the line and `kind`, "OBJ" or "MTL").
template <typename F>
void for_each_line(std::string_view text, const std::string& name, const char* kind, F&& f) {
  long line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    for (const char ch : line) {
      const auto c = static_cast<unsigned char>(ch);
      if ((c < 0x20 && c != '\t' && c != '\r' && c != '\f' && c != '\v') || c == 0x7f)
        throw Error(name, line_no, std::string("binary data: this is not a text ") + kind + " file");
    }
    f(line_no, line);
  }
}

/// Parses a number of an MTL statement.
double mtl_number(std::string_view& rest, const std::string& name, long line_no, std::string_view what) {
  const std::string_view tok = next_token(rest);
  double x = 0;
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
  if (tok.empty() || ec != std::errc() || ptr != tok.data() + tok.size() || !std::isfinite(x))
    throw Error(name, line_no, "malformed " + std::string(what) + " '" + std::string(tok) + "'");
  return x;
}

constexpr const char* kSeeThroughSuffix = " (see-through)";

}  // namespace

std::vector<std::string> see_through_materials(std::string_view mtl, const std::string& name) {
  std::vector<std::string> out;
  std::string current;
  bool current_see_through = false;
  auto close = [&] {
    if (!current.empty() && current_see_through) out.push_back(current);
  };
  for_each_line(mtl, name, "MTL", [&](long line_no, std::string_view line) {
    std::string_view rest = line;
    const std::string_view kw = next_token(rest);
    if (kw == "newmtl") {
      close();
      current = std::string(trim(rest));
      if (current.empty()) throw Error(name, line_no, "newmtl needs a material name");
      current_see_through = false;
    } else if (kw == "d" || kw == "Tr" || kw == "illum") {
      if (current.empty()) throw Error(name, line_no, std::string(kw) + " before any newmtl");
      std::string_view args = rest;
      if (kw == "d" && trim(args).substr(0, 5) == "-halo") next_token(args);  // d -halo F: the factor follows
      const double v = mtl_number(args, name, line_no, kw == "illum" ? "illumination model" : "transparency");
      if (kw == "d") current_see_through |= v < 1;
      if (kw == "Tr") current_see_through |= v > 0;
      if (kw == "illum") current_see_through |= v == 4 || v == 6 || v == 7 || v == 9;
    }
  });
  close();
  return out;
}

RawMesh read_obj(std::istream& in, const std::string& name, const MaterialLibraryReader& read_mtl) {
  std::string text = read_all(in, name);
  RawMesh mesh;
  std::unordered_map<std::string, uint32_t> group_index;
  constexpr uint32_t kUngrouped = 0xffffffffu;
  uint32_t current_group = kUngrouped;
  bool any_ungrouped = false;
  std::vector<uint32_t> polygon;
  // Materials: the see-through ones from the mtllib files; faces under one of them go to
  // "GROUP (see-through)".
  std::unordered_map<std::string, bool> see_through;
  std::string group_name;      // the current o/g name ("" before any)
  bool in_see_through = false;  // the current usemtl material is see-through
  std::vector<uint8_t> group_see_through;
  std::vector<size_t> group_faces;  // faces per group
  auto group_id = [&](const std::string& g, bool glass) {
    const std::string full = glass ? (g.empty() ? "default" : g) + kSeeThroughSuffix : g;
    auto [it, inserted] = group_index.emplace(full, static_cast<uint32_t>(mesh.group_names.size()));
    if (inserted) {
      mesh.group_names.push_back(full);
      group_see_through.push_back(glass);
      group_faces.push_back(0);
    }
    return it->second;
  };
  auto select_group = [&] {
    current_group = group_name.empty() && !in_see_through ? kUngrouped : group_id(group_name, in_see_through);
  };

  for_each_line(text, name, "OBJ", [&](long line_no, std::string_view line) {
    std::string_view rest = line;
    const std::string_view kw = next_token(rest);
    if (kw.empty()) return;

    if (kw == "v") {
      double c[3];
      for (double& x : c) {
        const std::string_view tok = next_token(rest);
        if (tok.empty()) throw Error(name, line_no, "vertex needs three coordinates");
        const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
        if (ec == std::errc::result_out_of_range)
          throw Error(name, line_no, "coordinate '" + std::string(tok) + "' is out of range");
        if (ec != std::errc() || ptr != tok.data() + tok.size())
          throw Error(name, line_no, "malformed coordinate '" + std::string(tok) + "'");
        if (!std::isfinite(x)) throw Error(name, line_no, "NaN or infinite coordinate '" + std::string(tok) + "'");
        if (std::abs(x) > kMaxCoordinate)
          throw Error(name, line_no, "coordinate '" + std::string(tok) +
                                         "' is beyond what ray casting can represent (at most 1e18 in magnitude)");
      }
      mesh.vertices.push_back({c[0], c[1], c[2]});
    } else if (kw == "f") {
      polygon.clear();
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        const std::string_view index_text = tok.substr(0, tok.find('/'));
        long idx = 0;
        const auto [ptr, ec] = std::from_chars(index_text.data(), index_text.data() + index_text.size(), idx);
        if (ec != std::errc() || ptr != index_text.data() + index_text.size() || idx == 0)
          throw Error(name, line_no, "malformed face index '" + std::string(tok) + "'");
        const long n = static_cast<long>(mesh.vertices.size());
        const long resolved = idx > 0 ? idx - 1 : n + idx;
        if (resolved < 0 || resolved >= n)
          throw Error(name, line_no, "face index " + std::to_string(idx) + " out of range (" +
                                         std::to_string(n) + " vertices so far)");
        polygon.push_back(static_cast<uint32_t>(resolved));
      }
      if (polygon.size() < 3) throw Error(name, line_no, "face needs at least three vertices");
      if (current_group == kUngrouped) any_ungrouped = true;
      else ++group_faces[current_group];
      for (size_t i = 1; i + 1 < polygon.size(); ++i) {
        mesh.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
        mesh.triangle_group.push_back(current_group);
      }
    } else if (kw == "o" || kw == "g") {
      group_name = std::string(trim(rest));
      if (group_name.empty()) group_name = "unnamed";
      select_group();
    } else if (kw == "mtllib" && read_mtl) {
      for (std::string_view file = next_token(rest); !file.empty(); file = next_token(rest)) {
        std::vector<std::string> materials;
        try {
          materials = see_through_materials(read_mtl(std::string(file)), std::string(file));
        } catch (const Error& e) {
          throw Error(name, line_no, "material library '" + std::string(file) + "': " + e.what());
        }
        for (std::string& m : materials) see_through[std::move(m)] = true;
      }
    } else if (kw == "usemtl") {
      const auto it = see_through.find(std::string(trim(rest)));
      in_see_through = it != see_through.end();
      select_group();
    }
    // Other statements (vn, vt, s, l, ...) carry nothing we use.
  });

  if (mesh.group_names.empty()) {
    mesh.triangle_group.assign(mesh.triangles.size(), 0);
  } else if (any_ungrouped) {
    const uint32_t def = static_cast<uint32_t>(mesh.group_names.size());
    mesh.group_names.push_back("default");
    group_see_through.push_back(0);
    group_faces.push_back(1);
    for (uint32_t& g : mesh.triangle_group)
      if (g == kUngrouped) g = def;
  }
  if (std::find(group_see_through.begin(), group_see_through.end(), 1) != group_see_through.end()) {
    // A group whose faces are all see-through keeps its own name; the suffix only tells apart
    // the two parts of a group that mixes materials.
    const std::string suffix = kSeeThroughSuffix;
    for (size_t g = 0; g < group_see_through.size(); ++g) {
      if (!group_see_through[g]) continue;
      const std::string base = mesh.group_names[g].substr(0, mesh.group_names[g].size() - suffix.size());
      const auto it = group_index.find(base);
      const bool base_has_faces = it != group_index.end() ? group_faces[it->second] > 0 : (base == "default" && any_ungrouped);
      if (!base_has_faces) mesh.group_names[g] = base;  // an empty group of that name makes no object
    }
    mesh.group_occluder.resize(group_see_through.size());
    for (size_t g = 0; g < group_see_through.size(); ++g) mesh.group_occluder[g] = !group_see_through[g];
  }
  return mesh;
}

void write_obj(const Scene& scene, const std::string& path) {
  std::string out;
  out.reserve(scene.vertices.size() * 40 + scene.triangles.size() * 30);
  out += "# viewcells scene: " + scene.source + "\n";
  out += "# " + std::to_string(scene.objects.size()) + " objects, " +
         std::to_string(scene.triangles.size()) + " triangles\n";
  char buf[64];
  auto put_double = [&](double v) {
    const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest exact representation
    out.append(buf, r.ptr);
  };
  for (const Vec3& v : scene.vertices) {
    out += "v ";
    put_double(v.x);
    out += ' ';
    put_double(v.y);
    out += ' ';
    put_double(v.z);
    out += '\n';
  }
  // See-through objects get the material "see_through" of a material library beside the file
  // (dissolve 0.3), which read_obj turns back into non-occluding objects.
  const bool any_see_through = std::any_of(scene.objects.begin(), scene.objects.end(),
                                           [](const ObjectInfo& o) { return !o.occluder; });
  const std::filesystem::path mtl = std::filesystem::path(path).replace_extension(".mtl");
  std::unordered_set<std::string> opaque_names;
  for (const ObjectInfo& o : scene.objects)
    if (o.occluder) opaque_names.insert(o.name);
  if (any_see_through) out += "mtllib " + mtl.filename().string() + "\n";
  // Faces grouped by object, objects in id order, so reading back gives the same ids.
  std::vector<std::vector<uint32_t>> by_object(scene.objects.size());
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) by_object[scene.triangle_object[t]].push_back(t);
  for (size_t o = 0; o < by_object.size(); ++o) {
    std::string object_name = scene.objects[o].name;
    if (!scene.objects[o].occluder) {
      // "NAME (see-through)" beside an opaque "NAME" is written as NAME: the reader splits it off
      // again by its material (and names a see-through group alone by its own name).
      const std::string suffix = kSeeThroughSuffix;
      if (object_name.size() > suffix.size() && object_name.ends_with(suffix) &&
          opaque_names.count(object_name.substr(0, object_name.size() - suffix.size())))
        object_name.resize(object_name.size() - suffix.size());
      out += "o " + object_name + "\nusemtl see_through\n";
    } else {
      out += "o " + object_name + (any_see_through ? "\nusemtl opaque\n" : "\n");
    }
    for (uint32_t t : by_object[o]) {
      out += 'f';
      for (uint32_t v : scene.triangles[t]) {
        out += ' ';
        const auto r = std::to_chars(buf, buf + sizeof buf, v + 1);
        out.append(buf, r.ptr);
      }
      out += '\n';
    }
  }
  if (any_see_through)
    write_text_file(mtl.string(),
                    "# viewcells: materials of " + std::filesystem::path(path).filename().string() +
                        "\nnewmtl opaque\nd 1\nnewmtl see_through\nd 0.3\n");
  write_text_file(path, out);
}

}  // namespace viewcells
