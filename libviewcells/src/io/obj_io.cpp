// OBJ reading and writing. The reader is our own (not OpenMesh's) because it must keep `o`/`g`
// groups as objects and report the line of every error.
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>

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

}  // namespace

RawMesh read_obj(std::istream& in, const std::string& name) {
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(name, 0, "read error");
  RawMesh mesh;
  std::unordered_map<std::string, uint32_t> group_index;
  constexpr uint32_t kUngrouped = 0xffffffffu;
  uint32_t current_group = kUngrouped;
  bool any_ungrouped = false;
  std::vector<uint32_t> polygon;

  long line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    for (const char ch : line) {
      const auto c = static_cast<unsigned char>(ch);
      if ((c < 0x20 && c != '\t' && c != '\r' && c != '\f' && c != '\v') || c == 0x7f)
        throw Error(name, line_no, "binary data: this is not a text OBJ file");
    }
    std::string_view rest = line;
    const std::string_view kw = next_token(rest);
    if (kw.empty()) continue;

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
      for (size_t i = 1; i + 1 < polygon.size(); ++i) {
        mesh.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
        mesh.triangle_group.push_back(current_group);
      }
    } else if (kw == "o" || kw == "g") {
      std::string group(trim(rest));
      if (group.empty()) group = "unnamed";
      auto [it, inserted] = group_index.emplace(group, static_cast<uint32_t>(mesh.group_names.size()));
      if (inserted) mesh.group_names.push_back(group);
      current_group = it->second;
    }
    // Other statements (vn, vt, s, usemtl, mtllib, l, ...) carry nothing we use.
  }

  if (mesh.group_names.empty()) {
    mesh.triangle_group.assign(mesh.triangles.size(), 0);
  } else if (any_ungrouped) {
    const uint32_t def = static_cast<uint32_t>(mesh.group_names.size());
    mesh.group_names.push_back("default");
    for (uint32_t& g : mesh.triangle_group)
      if (g == kUngrouped) g = def;
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
  // Faces grouped by object, objects in id order, so reading back gives the same ids.
  std::vector<std::vector<uint32_t>> by_object(scene.objects.size());
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) by_object[scene.triangle_object[t]].push_back(t);
  for (size_t o = 0; o < by_object.size(); ++o) {
    out += "o " + scene.objects[o].name + "\n";
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
  write_text_file(path, out);
}

}  // namespace viewcells
