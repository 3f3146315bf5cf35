// The .pvs payload codec (pvs_payload.h): one writer and one reader for the toolkit and the
// engines' runtime.
#include "viewcells/format/pvs_payload.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "viewcells/format/id_lists.h"

namespace viewcells::format {

namespace {

[[noreturn]] void corrupt(const std::string& what) { throw FormatError("corrupt file: " + what); }

/// Little-endian appends.
class Writer {
 public:
  template <class T>
  void put(T v) {
    static_assert(std::is_arithmetic_v<T>);
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out_.append(b, sizeof(T));
  }
  void put_string(const std::string& s) {
    put<uint64_t>(s.size());
    out_ += s;
  }
  template <class T>
  void put_array(const std::vector<T>& v) {
    put<uint64_t>(v.size());
    for (T x : v) put<T>(x);
  }
  std::string& data() { return out_; }

 private:
  std::string out_;
};

/// Bounds-checked little-endian reads.
class Reader {
 public:
  explicit Reader(const std::string& data) : data_(data) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string get_string() {
    const uint64_t n = get<uint64_t>();
    need(n);
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  template <class T>
  std::vector<T> get_array(uint64_t max_count) {
    const uint64_t n = get<uint64_t>();
    if (n > max_count) corrupt("an array larger than the file");
    need(n * sizeof(T));
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), data_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return v;
  }
  uint32_t get_varint() {
    uint32_t v = 0;
    for (int shift = 0; shift < 35; shift += 7) {
      const uint8_t b = get<uint8_t>();
      v |= static_cast<uint32_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    corrupt("malformed varint");
  }
  bool at_end() const { return pos_ == data_.size(); }

 private:
  void need(uint64_t n) const {
    if (n > data_.size() - pos_) corrupt("payload ends early");
  }
  const std::string& data_;
  size_t pos_ = 0;
};

bool finite3(const double v[3]) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

/// Version 1's lists: each a LEB128 varint count, then the differences between successive ids
/// (minus one) as varints.
void put_varint(std::string& out, uint32_t v) {
  for (; v >= 0x80; v >>= 7) out.push_back(static_cast<char>((v & 0x7f) | 0x80));
  out.push_back(static_cast<char>(v));
}

void read_planes(Reader& r, PvsPayload& p, uint64_t max_items) {
  const uint64_t count = r.get<uint64_t>();
  if (count < 6 || count > max_items) corrupt("invalid plane count");
  p.planes.resize(count);
  for (PvsPlane& q : p.planes) {
    q.axis = r.get<int32_t>();
    for (double& x : q.normal) x = r.get<double>();
    q.offset = r.get<double>();
    for (auto& point : q.points)
      for (double& x : point) x = r.get<double>();
    if (q.axis < -1 || q.axis > 2 || !finite3(q.normal) || !std::isfinite(q.offset)) corrupt("invalid plane");
    // A general plane's side is decided exactly from its points: they must be numbers.
    if (q.axis < 0 && !(finite3(q.points[0]) && finite3(q.points[1]) && finite3(q.points[2])))
      corrupt("invalid plane");
  }
}

/// The BSP: every inner node has a plane and two later children, each node but the root is a
/// child once, every leaf is in a view cell.
void check_bsp(const PvsPayload& p) {
  const size_t nodes = p.nodes.size();
  std::vector<int> parents(nodes, 0);
  for (size_t n = 0; n < nodes; ++n) {
    const PvsNode& b = p.nodes[n];
    if (b.plane < 0) {
      if (b.child[0] != -1 || b.child[1] != -1) corrupt("BSP leaf " + std::to_string(n) + " has children");
      if (b.cell < 0 || static_cast<uint32_t>(b.cell) >= p.cell_count)
        corrupt("BSP leaf " + std::to_string(n) + " has no view cell");
      continue;
    }
    if (static_cast<uint64_t>(b.plane) >= p.planes.size() || b.cell != -1)
      corrupt("BSP node " + std::to_string(n) + " is invalid");
    for (int32_t c : b.child) {
      if (c <= static_cast<int64_t>(n) || static_cast<uint64_t>(c) >= nodes)
        corrupt("BSP node " + std::to_string(n) + " has a bad child");
      ++parents[c];
    }
  }
  for (size_t n = 1; n < nodes; ++n)
    if (parents[n] != 1) corrupt("BSP node " + std::to_string(n) + " is not in the tree once");
}

void read_lists(const std::string& lists, uint32_t version, PvsPayload& p, std::vector<uint64_t>* node_bits) {
  const size_t total = p.parent.size();
  p.stored.assign(total, {});
  if (version == 1) {
    Reader lr(lists);
    for (auto& ids : p.stored) {
      const uint32_t n = lr.get_varint();
      if (n > p.object_count) corrupt("a list holds more entries than there are objects");
      ids.resize(n);
      uint64_t previous = 0;
      for (uint32_t i = 0; i < n; ++i) {
        const uint64_t id = (i ? previous + 1 : 0) + lr.get_varint();
        if (id >= p.object_count) corrupt("object id " + std::to_string(id) + " out of range");
        ids[i] = static_cast<uint32_t>(id);
        previous = id;
      }
    }
    if (!lr.at_end()) corrupt("trailing bytes after the PVS lists");
    return;
  }
  id_lists::BitReader lr(lists.data(), lists.size());
  if (node_bits) node_bits->reserve(total);
  for (size_t n = 0; n < total; ++n) {
    if (node_bits) node_bits->push_back(lr.position());
    if (!id_lists::get_list(lr, p.object_count, p.stored[n]))
      corrupt("malformed PVS list of hierarchy node " + std::to_string(n));
  }
  if (!lr.at_end()) corrupt("trailing bytes after the PVS lists");
}

/// No cell's path through the hierarchy repeats an object (what the nodes of a path keep is
/// disjoint by construction); sized first, so that a path can never hold more than the objects.
/// Each object is stamped with the last cell that met it, in one pass over the entries; when the
/// objects far outnumber the payload's bytes (a hostile count), each path is sorted instead, so
/// that memory stays bounded by the payload.
void check_paths(const PvsPayload& p, size_t payload_bytes) {
  const bool stamps = p.object_count <= 64 * uint64_t{payload_bytes} + 4096;
  std::vector<uint32_t> stamp(stamps ? p.object_count : 0, UINT32_MAX), cell;
  for (uint32_t c = 0; c < p.cell_count; ++c) {
    uint64_t size = 0;
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = p.parent[n]) size += p.stored[n].size();
    if (size > p.object_count) corrupt("cell " + std::to_string(c) + " repeats an object");
    if (stamps) {
      for (int32_t n = static_cast<int32_t>(c); n >= 0; n = p.parent[n])
        for (uint32_t id : p.stored[n]) {
          if (stamp[id] == c) corrupt("cell " + std::to_string(c) + " repeats an object");
          stamp[id] = c;
        }
      continue;
    }
    cell.clear();
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = p.parent[n])
      cell.insert(cell.end(), p.stored[n].begin(), p.stored[n].end());
    std::sort(cell.begin(), cell.end());
    if (std::adjacent_find(cell.begin(), cell.end()) != cell.end())
      corrupt("cell " + std::to_string(c) + " repeats an object");
  }
}

}  // namespace

std::string encode_pvs_payload(const PvsPayload& p, uint32_t version) {
  if (version != 1 && version != kPvsVersion)
    throw FormatError("cannot write .pvs format " + std::to_string(version) + " (1 or " +
                      std::to_string(kPvsVersion) + ")");
  // The coding holds only sorted ids below the object count: refuse to write anything else.
  for (size_t n = 0; n < p.stored.size(); ++n) {
    const std::vector<uint32_t>& l = p.stored[n];
    for (size_t i = 0; i < l.size(); ++i)
      if (l[i] >= p.object_count || (i && l[i - 1] >= l[i]))
        throw FormatError("the PVS list of hierarchy node " + std::to_string(n) + " is not sorted ids below the " +
                          std::to_string(p.object_count) + " objects");
  }
  Writer w;
  w.put<uint64_t>(p.fingerprint);
  w.put<uint32_t>(p.object_count);
  w.put<uint64_t>(p.names.size());
  for (const std::string& n : p.names) w.put_string(n);
  w.put_string(p.rule);
  for (double x : p.lo) w.put(x);
  for (double x : p.hi) w.put(x);
  w.put<uint64_t>(p.planes.size());
  for (const PvsPlane& q : p.planes) {
    w.put<int32_t>(q.axis);
    for (double x : q.normal) w.put(x);
    w.put(q.offset);
    for (const auto& point : q.points)
      for (double x : point) w.put(x);
  }
  w.put<uint64_t>(p.nodes.size());
  for (const PvsNode& b : p.nodes) {
    w.put<int32_t>(b.plane);
    w.put<int32_t>(b.child[0]);
    w.put<int32_t>(b.child[1]);
    w.put<int32_t>(b.cell);
  }
  w.put<uint32_t>(p.cell_count);
  w.put_array(p.parent);
  w.put_array(p.mht);
  if (version == 1) {
    std::string lists;
    for (const auto& l : p.stored) {
      put_varint(lists, static_cast<uint32_t>(l.size()));
      for (size_t i = 0; i < l.size(); ++i) put_varint(lists, i ? l[i] - l[i - 1] - 1 : l[i]);
    }
    w.put_string(lists);
  } else {
    w.put_string(id_lists::encode(p.stored, p.object_count));
  }
  return std::move(w.data());
}

PvsPayload decode_pvs_payload(const std::string& payload, uint32_t version, std::vector<uint64_t>* node_bits,
                              std::string* coded) {
  if (version != 1 && version != kPvsVersion)
    throw FormatError("unsupported .pvs version " + std::to_string(version));
  Reader r(payload);
  const uint64_t max_items = payload.size();
  PvsPayload p;
  p.fingerprint = r.get<uint64_t>();
  p.object_count = r.get<uint32_t>();
  const uint64_t names = r.get<uint64_t>();
  if (names != 0 && names != p.object_count) corrupt("object names do not match the object count");
  for (uint64_t i = 0; i < names; ++i) p.names.push_back(r.get_string());
  p.rule = r.get_string();
  for (double& x : p.lo) x = r.get<double>();
  for (double& x : p.hi) x = r.get<double>();
  // Finite corners and a positive volume in double (as the toolkit's Box3::volume).
  double volume = 1;
  bool box_ok = finite3(p.lo) && finite3(p.hi);
  for (int k = 0; k < 3; ++k) {
    box_ok &= p.lo[k] <= p.hi[k];
    volume *= p.hi[k] - p.lo[k];
  }
  if (!box_ok || !(volume > 0)) corrupt("invalid view box");
  read_planes(r, p, max_items);
  const uint64_t nodes = r.get<uint64_t>();
  if (nodes == 0 || nodes > max_items || nodes % 2 == 0) corrupt("invalid node count");
  p.nodes.resize(nodes);
  for (PvsNode& b : p.nodes) {
    b.plane = r.get<int32_t>();
    b.child[0] = r.get<int32_t>();
    b.child[1] = r.get<int32_t>();
    b.cell = r.get<int32_t>();
  }
  p.cell_count = r.get<uint32_t>();
  p.parent = r.get_array<int32_t>(max_items);
  p.mht = r.get_array<uint32_t>(max_items);
  std::string lists = r.get_string();
  if (!r.at_end()) corrupt("trailing bytes");
  const size_t total = p.parent.size();
  if (p.cell_count == 0 || p.cell_count > total || p.mht.size() != p.cell_count) corrupt("invalid view cell count");
  check_bsp(p);
  for (size_t n = 0; n < total; ++n) {
    const int32_t up = p.parent[n];
    if (up != -1 && (up <= static_cast<int64_t>(n) || static_cast<size_t>(up) >= total))
      corrupt("hierarchy node " + std::to_string(n) + " has a bad parent");
  }
  read_lists(lists, version, p, version == 1 ? nullptr : node_bits);
  check_paths(p, payload.size());
  if (coded && version != 1) *coded = std::move(lists);
  return p;
}

}  // namespace viewcells::format
