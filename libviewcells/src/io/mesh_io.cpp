// PLY, OFF and STL readers (load_scene, in scene_io.cpp, picks them). Our own rather than
// OpenMesh's: those looped forever or allocated without bound on a cut header or a huge
// declared count, and invented faces past the end of a file. Here every declared count is
// checked against the bytes that are left before anything is allocated or looped over, and
// every error names the file and, for text, the line.
#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"

namespace viewcells {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Lines and whitespace-separated tokens of a text, with the line number for errors.
class TextReader {
 public:
  /// `first_line`: lines before the text (for a part of a file).
  TextReader(std::string_view text, const std::string& name, long first_line = 0)
      : text_(text), name_(name), line_(first_line) {}

  /// The next token, crossing line ends; empty at the end of the text.
  std::string_view token() {
    while (pos_ < text_.size() && (is_blank(text_[pos_]) || text_[pos_] == '\n')) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    const size_t start = pos_;
    while (pos_ < text_.size() && !is_blank(text_[pos_]) && text_[pos_] != '\n') ++pos_;
    return text_.substr(start, pos_ - start);
  }
  /// The next line with content, '#' comments removed; false at the end of the text.
  bool content_line(std::string_view& line) {
    while (pos_ < text_.size()) {
      size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      line = text_.substr(pos_, end - pos_);
      pos_ = std::min(end + 1, text_.size());
      ++line_;
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      if (std::any_of(line.begin(), line.end(), [](char c) { return !is_blank(c); })) return true;
    }
    return false;
  }
  size_t bytes_left() const { return text_.size() - pos_; }
  long line() const { return line_; }
  [[noreturn]] void fail(const std::string& what) const { throw Error(name_, line_, what); }

  double number(std::string_view tok) const {
    if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
    double x = 0;
    const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
    if (tok.empty()) fail("a number is missing");
    if (ec == std::errc::result_out_of_range) fail("coordinate '" + std::string(tok) + "' is out of range");
    if (ec != std::errc() || ptr != tok.data() + tok.size()) fail("malformed number '" + std::string(tok) + "'");
    if (!std::isfinite(x)) fail("NaN or infinite coordinate '" + std::string(tok) + "'");
    if (std::abs(x) > kMaxCoordinate)
      fail("coordinate '" + std::string(tok) + "' is beyond what ray casting can represent (at most 1e18 in magnitude)");
    return x;
  }
  uint64_t count(std::string_view tok, const char* what) const {
    if (tok.empty()) fail(std::string("the ") + what + " is missing");
    if (tok[0] == '-') fail(std::string("negative ") + what + " '" + std::string(tok) + "'");
    uint64_t n = 0;
    const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), n);
    if (ec == std::errc::result_out_of_range) fail(std::string(what) + " '" + std::string(tok) + "' is too large");
    if (ec != std::errc() || ptr != tok.data() + tok.size())
      fail(std::string("malformed ") + what + " '" + std::string(tok) + "'");
    return n;
  }

 private:
  std::string_view text_;
  const std::string& name_;
  size_t pos_ = 0;
  long line_ = 0;
};

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const size_t j = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > j) out.push_back(line.substr(j, i - j));
  }
  return out;
}

/// Refuses a declared count that the rest of the file cannot hold at min_bytes per item.
void check_room(uint64_t count, uint64_t min_bytes, uint64_t bytes_left, const std::string& name, long line,
                const std::string& what) {
  if (count > bytes_left / std::max<uint64_t>(min_bytes, 1))
    throw Error(name, line, "declares " + std::to_string(count) + " " + what + ", but only " +
                                std::to_string(bytes_left) + " bytes follow (truncated or malformed)");
}

/// Appends the fan triangulation of `polygon` (indices already checked).
void add_polygon(RawMesh& mesh, const std::vector<uint32_t>& polygon) {
  for (size_t i = 1; i + 1 < polygon.size(); ++i) mesh.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
}

// ---------------------------------------------------------------------------------- PLY

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool parse_ply_type(std::string_view s, PlyType& t) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},     {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},   {"short", PlyType::kInt16},   {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16}, {"uint16", PlyType::kUint16}, {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUint32},   {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [n, type] : names)
    if (s == n) return t = type, true;
  return false;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8: case PlyType::kUint8: return 1;
    case PlyType::kInt16: case PlyType::kUint16: return 2;
    case PlyType::kInt32: case PlyType::kUint32: case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 1;
}

bool ply_integral(PlyType t) { return t != PlyType::kFloat32 && t != PlyType::kFloat64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  uint64_t min_bytes() const {  // binary: every list empty
    uint64_t n = 0;
    for (const PlyProperty& p : properties) n += ply_size(p.list ? p.count_type : p.type);
    return n;
  }
};

/// Reads values of a PLY body: binary (either byte order) or ASCII tokens.
class PlyValues {
 public:
  PlyValues(std::string_view body, int format, const std::string& name, TextReader* text)
      : body_(body), format_(format), name_(name), text_(text) {}
  double get(PlyType t) {
    if (text_) {
      const std::string_view tok = text_->token();
      if (tok.empty()) text_->fail("the file ends inside its data (truncated)");
      if (!ply_integral(t)) return text_->number(tok);
      int64_t v = 0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc() || ptr != tok.data() + tok.size()) text_->fail("malformed integer '" + std::string(tok) + "'");
      return static_cast<double>(v);
    }
    const size_t n = ply_size(t);
    if (n > body_.size() - pos_) throw Error(name_, 0, "the file ends inside its data (truncated)");
    unsigned char b[8];
    std::memcpy(b, body_.data() + pos_, n);
    pos_ += n;
    if ((format_ == 2) == (std::endian::native == std::endian::little)) std::reverse(b, b + n);
    auto as = [&](auto v) {
      std::memcpy(&v, b, sizeof v);
      return static_cast<double>(v);
    };
    switch (t) {
      case PlyType::kInt8: return as(int8_t{});
      case PlyType::kUint8: return as(uint8_t{});
      case PlyType::kInt16: return as(int16_t{});
      case PlyType::kUint16: return as(uint16_t{});
      case PlyType::kInt32: return as(int32_t{});
      case PlyType::kUint32: return as(uint32_t{});
      case PlyType::kFloat32: return as(float{});
      case PlyType::kFloat64: return as(double{});
    }
    return 0;
  }
  uint64_t bytes_left() const { return text_ ? text_->bytes_left() : body_.size() - pos_; }
  long line() const { return text_ ? text_->line() : 0; }
  [[noreturn]] void fail(const std::string& what) const { throw Error(name_, line(), what); }

 private:
  std::string_view body_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  const std::string& name_;
  TextReader* text_;
  size_t pos_ = 0;
};

}  // namespace

RawMesh read_ply(std::string_view bytes, const std::string& name) {
  // Header: text lines up to end_header, which must come within the file.
  TextReader header(bytes, name);
  std::string_view line;
  if (!header.content_line(line) || split(line) != std::vector<std::string_view>{"ply"})
    header.fail("not a PLY file (no 'ply' on the first line)");
  int format = -1;
  std::vector<PlyElement> elements;
  bool ended = false;
  size_t body_start = 0;
  while (!ended) {
    if (!header.content_line(line)) throw Error(name, header.line(), "the header has no end_header (truncated)");
    const std::vector<std::string_view> t = split(line);
    if (t[0] == "end_header") {
      ended = true;
      body_start = bytes.size() - header.bytes_left();
    } else if (t[0] == "format") {
      if (t.size() < 2) header.fail("format needs a name");
      if (t[1] == "ascii") format = 0;
      else if (t[1] == "binary_little_endian") format = 1;
      else if (t[1] == "binary_big_endian") format = 2;
      else header.fail("unknown PLY format '" + std::string(t[1]) + "'");
    } else if (t[0] == "element") {
      if (t.size() != 3) header.fail("element needs a name and a count");
      elements.push_back({std::string(t[1]), header.count(t[2], "element count"), {}});
    } else if (t[0] == "property") {
      if (elements.empty()) header.fail("property before any element");
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        p.list = true;
        if (!parse_ply_type(t[2], p.count_type) || !parse_ply_type(t[3], p.type)) header.fail("unknown list types");
        if (!ply_integral(p.count_type)) header.fail("a list count must be an integer type");
        p.name = t[4];
      } else if (t.size() == 3) {
        if (!parse_ply_type(t[1], p.type)) header.fail("unknown property type '" + std::string(t[1]) + "'");
        p.name = t[2];
      } else {
        header.fail("malformed property line");
      }
      elements.back().properties.push_back(p);
    } else if (t[0] != "comment" && t[0] != "obj_info") {
      header.fail("unknown header line '" + std::string(t[0]) + "'");
    }
  }
  if (format < 0) header.fail("the header has no format line");
  const long header_lines = header.line();

  RawMesh mesh;
  uint64_t vertex_count = 0;
  for (const PlyElement& e : elements)
    if (e.name == "vertex") vertex_count = e.count;
  TextReader text(bytes.substr(body_start), name, header_lines);
  PlyValues values(bytes.substr(body_start), format, name, format == 0 ? &text : nullptr);
  std::vector<uint32_t> polygon;
  for (const PlyElement& e : elements) {
    if (e.count > 0 && e.properties.empty()) header.fail("element '" + e.name + "' has no properties");
    // ASCII: at least two bytes per value (a digit and a separator); binary: its fixed part.
    const uint64_t min_bytes = format == 0 ? 2 * e.properties.size() : e.min_bytes();
    check_room(e.count, min_bytes, values.bytes_left(), name, values.line(), e.name + " elements");
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& p = e.properties[k];
      for (int c = 0; c < 3; ++c)
        if (!p.list && p.name == std::string(1, static_cast<char>('x' + c))) xyz[c] = static_cast<int>(k);
      if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) indices = static_cast<int>(k);
    }
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)) header.fail("vertex element lacks x, y or z");
    if (is_face && indices < 0) header.fail("face element lacks a vertex_indices list");
    if (is_face && !ply_integral(e.properties[indices].type)) header.fail("vertex indices must be integers");
    if (is_vertex) mesh.vertices.reserve(e.count);
    for (uint64_t i = 0; i < e.count; ++i) {
      double c[3] = {0, 0, 0};
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.list) {
          const double v = values.get(p.type);
          for (int a = 0; a < 3; ++a)
            if (static_cast<int>(k) == xyz[a]) c[a] = v;
          continue;
        }
        const double n = values.get(p.count_type);
        if (n < 0) values.fail("negative list length in " + e.name + " " + std::to_string(i));
        const uint64_t len = static_cast<uint64_t>(n);
        check_room(len, format == 0 ? 2 : ply_size(p.type), values.bytes_left(), name,
                   values.line(), "list items");
        const bool wanted = is_face && static_cast<int>(k) == indices;
        if (wanted) polygon.clear();
        for (uint64_t j = 0; j < len; ++j) {
          const double v = values.get(p.type);
          if (!wanted) continue;
          if (!(v >= 0 && static_cast<uint64_t>(v) < vertex_count))
            values.fail("face " + std::to_string(i) + ": vertex index " + std::to_string(static_cast<int64_t>(v)) +
                        " out of range (" + std::to_string(vertex_count) + " vertices)");
          polygon.push_back(static_cast<uint32_t>(v));
        }
        if (wanted) {
          if (polygon.size() < 3) values.fail("face " + std::to_string(i) + " has fewer than three vertices");
          add_polygon(mesh, polygon);
        }
      }
      if (is_vertex) {
        for (double v : c)
          if (!std::isfinite(v)) values.fail("vertex " + std::to_string(i) + ": NaN or infinite coordinate");
        mesh.vertices.push_back({c[0], c[1], c[2]});
      }
    }
  }
  return mesh;
}

// ---------------------------------------------------------------------------------- OFF

RawMesh read_off(std::string_view bytes, const std::string& name) {
  TextReader in(bytes, name);
  std::string_view line;
  if (!in.content_line(line)) in.fail("empty file");
  std::vector<std::string_view> t = split(line);
  // [ST][C][N]OFF; 4OFF and nOFF (other dimensions) and binary OFF are not read.
  const std::string_view magic = t[0];
  const bool off = magic.size() >= 3 && magic.substr(magic.size() - 3) == "OFF" &&
                   magic.substr(0, magic.size() - 3).find_first_not_of("STCN") == std::string_view::npos;
  if (!off) in.fail("not an OFF file (it starts with '" + std::string(magic.substr(0, 32)) + "')");
  if (t.size() > 1 && t[1] == "BINARY") in.fail("binary OFF is not supported; save it as text");
  t.erase(t.begin());
  if (t.empty()) {
    if (!in.content_line(line)) in.fail("the file ends before its vertex and face counts (truncated)");
    t = split(line);
  }
  if (t.size() < 2) in.fail("the counts line needs the numbers of vertices and faces");
  const uint64_t nv = in.count(t[0], "vertex count"), nf = in.count(t[1], "face count");
  // At least "0 0 0\n" per vertex and "3 0 1 2\n" per face.
  check_room(nv, 6, in.bytes_left(), name, in.line(), "vertices");
  check_room(nf, 8, in.bytes_left(), name, in.line(), "faces");
  if (nv > UINT32_MAX) in.fail("more than 2^32 vertices");
  RawMesh mesh;
  mesh.vertices.reserve(nv);
  for (uint64_t i = 0; i < nv; ++i) {
    if (!in.content_line(line))
      in.fail("the header declares " + std::to_string(nv) + " vertices, the file holds " + std::to_string(i) +
              " (truncated)");
    t = split(line);
    if (t.size() < 3) in.fail("a vertex needs three coordinates");
    mesh.vertices.push_back({in.number(t[0]), in.number(t[1]), in.number(t[2])});
  }
  std::vector<uint32_t> polygon;
  for (uint64_t i = 0; i < nf; ++i) {
    if (!in.content_line(line))
      in.fail("the header declares " + std::to_string(nf) + " faces, the file holds " + std::to_string(i) +
              " (truncated)");
    t = split(line);
    const uint64_t n = in.count(t[0], "face size");
    if (n < 3) in.fail("a face needs at least three vertices");
    if (n > t.size() - 1)
      in.fail("the face declares " + std::to_string(n) + " vertices, the line holds " + std::to_string(t.size() - 1));
    polygon.clear();
    for (uint64_t k = 1; k <= n; ++k) {
      const uint64_t v = in.count(t[k], "vertex index");
      if (v >= nv) in.fail("vertex index " + std::to_string(v) + " out of range (" + std::to_string(nv) + " vertices)");
      polygon.push_back(static_cast<uint32_t>(v));
    }
    add_polygon(mesh, polygon);
  }
  return mesh;
}

// ---------------------------------------------------------------------------------- STL

RawMesh read_stl(std::string_view bytes, const std::string& name) {
  RawMesh mesh;
  uint32_t declared = 0;
  if (bytes.size() >= 84) std::memcpy(&declared, bytes.data() + 80, 4);  // little-endian, as written
  const bool binary = bytes.size() >= 84 && bytes.size() == 84 + 50 * static_cast<uint64_t>(declared);
  size_t first = 0;
  while (first < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[first]))) ++first;
  if (!binary && bytes.substr(first, 5) != "solid") {
    if (bytes.size() < 84) throw Error(name, 0, "not an STL file (too short for binary STL, no 'solid')");
    throw Error(name, 0, "truncated binary STL: " + std::to_string(declared) + " triangles declared (" +
                             std::to_string(84 + 50 * static_cast<uint64_t>(declared)) + " bytes), " +
                             std::to_string(bytes.size()) + " bytes found");
  }
  if (binary) {
    mesh.vertices.reserve(3 * static_cast<size_t>(declared));
    mesh.triangles.reserve(declared);
    for (uint32_t i = 0; i < declared; ++i) {
      const char* p = bytes.data() + 84 + 50 * static_cast<size_t>(i) + 12;  // past the normal
      for (int k = 0; k < 3; ++k) {
        float c[3];
        std::memcpy(c, p + 12 * k, 12);
        if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
          throw Error(name, 0, "triangle " + std::to_string(i) + ": NaN or infinite coordinate");
        mesh.vertices.push_back({c[0], c[1], c[2]});
      }
      const uint32_t v = 3 * i;
      mesh.triangles.push_back({v, v + 1, v + 2});
    }
    return mesh;
  }
  TextReader in(bytes, name);
  auto expect = [&](std::string_view word) {
    const std::string_view tok = in.token();
    if (tok != word)
      in.fail(tok.empty() ? "the file ends inside a facet (truncated ASCII STL, no endsolid)"
                          : "expected '" + std::string(word) + "', found '" + std::string(tok.substr(0, 32)) + "'");
  };
  std::string_view line;
  in.content_line(line);  // "solid [name]"
  for (;;) {
    const std::string_view tok = in.token();
    if (tok.empty()) in.fail("truncated ASCII STL (no endsolid)");
    if (tok == "endsolid") {
      in.content_line(line);  // the rest of its line (the name), then maybe another solid
      std::string_view next;
      if (!in.content_line(next)) break;
      if (split(next)[0] != "solid") in.fail("expected 'solid' after 'endsolid'");
      continue;
    }
    if (tok != "facet") in.fail("expected 'facet' or 'endsolid', found '" + std::string(tok.substr(0, 32)) + "'");
    expect("normal");
    for (int k = 0; k < 3; ++k) in.number(in.token());
    expect("outer");
    expect("loop");
    const uint32_t v = static_cast<uint32_t>(mesh.vertices.size());
    for (int k = 0; k < 3; ++k) {
      expect("vertex");
      const double x = in.number(in.token()), y = in.number(in.token()), z = in.number(in.token());
      mesh.vertices.push_back({x, y, z});
    }
    expect("endloop");
    expect("endfacet");
    mesh.triangles.push_back({v, v + 1, v + 2});
  }
  return mesh;
}

}  // namespace viewcells
