// The viewcells runtime reader (runtime.h): the .pvs container and payload as the toolkit
// writes them (libviewcells/src/pvs/pvs.cpp, core/binary_file.cpp), read with zstd alone.
// Every count and index is checked before it is used; nothing in a file can make the reader
// read out of bounds, loop or allocate beyond what the file's own size implies.
#include "viewcells/runtime.h"

#include "id_lists.h"

#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <sys/mman.h>
#include <sys/stat.h>
#include <vector>

namespace {

struct Vec {
  double v[3];
};

/// A BSP node as location walks it: 16 bytes, laid out in preorder so that the negative
/// child follows its parent. `right` is the positive child, or 0 for a leaf (the root is
/// never a child). An inner node compares coordinate `meta >> 30` (0-2) with `offset`, or
/// when that is 3 asks the exact predicate of general plane `meta & kIndex`. A leaf's `meta`
/// is its view cell, and `list` locates the cell's visible objects in the ids array.
struct Node {
  union {
    double offset;
    uint32_t list[2];  // first, count
  };
  uint32_t meta;
  uint32_t right;
};
constexpr uint32_t kIndex = (1u << 30) - 1;

struct GeneralPlane {
  Vec a, b, c;  // the three points that define it (the toolkit's Plane::points)
};

class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

uint64_t fnv1a64(const std::string& bytes) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

/// Bounds-checked little-endian reads of a payload.
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
    if (n > max_count) throw FileError("corrupt file: an array larger than the file");
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
    throw FileError("corrupt file: malformed varint");
  }
  bool at_end() const { return pos_ == data_.size(); }

 private:
  void need(uint64_t n) const {
    if (n > data_.size() - pos_) throw FileError("corrupt file: payload ends early");
  }
  const std::string& data_;
  size_t pos_ = 0;
};

/// The container: magic, version (low 16 bits; the third byte names the writer's Embree
/// ISA), payload size, FNV-1a checksum, compressed size, zstd frame.
std::string read_container(const std::string& path, uint32_t& version) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) throw FileError("no such file");
  if (!S_ISREG(st.st_mode)) throw FileError("not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot open file");
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (file.size() < 32) throw FileError("not a .pvs file (too short)");
  if (std::memcmp(file.data(), "VPVS", 4) != 0) throw FileError("not a .pvs file (wrong magic)");
  Reader r(file);
  r.get<uint32_t>();
  const uint32_t tagged = r.get<uint32_t>();
  if (tagged >> 24) throw FileError("corrupt file: malformed version field");
  version = tagged & 0xffff;
  if (version != 1 && version != 2)
    throw FileError("format version " + std::to_string(version) + " is not supported (this reader reads 1 and 2)");
  const uint64_t raw_size = r.get<uint64_t>(), checksum = r.get<uint64_t>(), csize = r.get<uint64_t>();
  if (csize != file.size() - 32) throw FileError("corrupt file: compressed size does not match (truncated?)");
  if (ZSTD_getFrameContentSize(file.data() + 32, csize) != raw_size)
    throw FileError("corrupt file: compressed frame does not match header");
  if (raw_size > 65536 * (csize + 64)) throw FileError("corrupt file: impossible decompressed size");
  std::string payload(raw_size, '\0');
  const size_t got = ZSTD_decompress(payload.data(), raw_size, file.data() + 32, csize);
  if (ZSTD_isError(got) || got != raw_size) throw FileError("corrupt file: decompression failed");
  if (fnv1a64(payload) != checksum) throw FileError("corrupt file: checksum mismatch");
  return payload;
}

// ------------------------------------------------------------ exact orientation predicate

/// Signed integers of any size (32-bit limbs, least significant first), for the exact
/// fallback: a double is an integer times a power of two, so with every coordinate of a
/// predicate on the grid of the smallest power among them, the determinant is an exact
/// integer sum whatever the magnitudes (no overflow, no underflow, denormals included).
struct BigInt {
  bool negative = false;
  std::vector<uint32_t> limbs;  // magnitude; empty for zero

  void trim() {
    while (!limbs.empty() && limbs.back() == 0) limbs.pop_back();
    if (limbs.empty()) negative = false;
  }
  /// |m| * 2^shift, with the sign of `negative`.
  static BigInt from(uint64_t m, int shift, bool negative) {
    BigInt b;
    b.negative = negative;
    b.limbs.assign(static_cast<size_t>(shift / 32) + 3, 0);
    const int bit = shift % 32;  // m < 2^53, so m 2^bit < 2^85: three limbs
    const uint64_t low = m << bit, high = bit ? m >> (64 - bit) : 0;
    b.limbs[shift / 32] = static_cast<uint32_t>(low);
    b.limbs[shift / 32 + 1] = static_cast<uint32_t>(low >> 32);
    b.limbs[shift / 32 + 2] = static_cast<uint32_t>(high);
    b.trim();
    return b;
  }
};

int compare_magnitude(const BigInt& a, const BigInt& b) {
  if (a.limbs.size() != b.limbs.size()) return a.limbs.size() < b.limbs.size() ? -1 : 1;
  for (size_t k = a.limbs.size(); k-- > 0;)
    if (a.limbs[k] != b.limbs[k]) return a.limbs[k] < b.limbs[k] ? -1 : 1;
  return 0;
}

BigInt multiply(const BigInt& a, const BigInt& b) {
  BigInt r;
  if (a.limbs.empty() || b.limbs.empty()) return r;
  r.negative = a.negative != b.negative;
  r.limbs.assign(a.limbs.size() + b.limbs.size(), 0);
  for (size_t i = 0; i < a.limbs.size(); ++i) {
    uint64_t carry = 0;
    for (size_t j = 0; j < b.limbs.size(); ++j) {
      const uint64_t t = static_cast<uint64_t>(a.limbs[i]) * b.limbs[j] + r.limbs[i + j] + carry;
      r.limbs[i + j] = static_cast<uint32_t>(t);
      carry = t >> 32;
    }
    r.limbs[i + b.limbs.size()] = static_cast<uint32_t>(carry);
  }
  r.trim();
  return r;
}

BigInt add(const BigInt& a, const BigInt& b) {
  BigInt r;
  if (a.negative == b.negative) {
    r.negative = a.negative;
    r.limbs.assign(std::max(a.limbs.size(), b.limbs.size()) + 1, 0);
    uint64_t carry = 0;
    for (size_t k = 0; k + 1 < r.limbs.size(); ++k) {
      const uint64_t t = carry + (k < a.limbs.size() ? a.limbs[k] : 0) + (k < b.limbs.size() ? b.limbs[k] : 0);
      r.limbs[k] = static_cast<uint32_t>(t);
      carry = t >> 32;
    }
    r.limbs.back() = static_cast<uint32_t>(carry);
  } else {
    const bool a_larger = compare_magnitude(a, b) >= 0;
    const BigInt& big = a_larger ? a : b;
    const BigInt& small = a_larger ? b : a;
    r.negative = big.negative;
    r.limbs.assign(big.limbs.size(), 0);
    int64_t borrow = 0;
    for (size_t k = 0; k < big.limbs.size(); ++k) {
      int64_t t = static_cast<int64_t>(big.limbs[k]) - (k < small.limbs.size() ? small.limbs[k] : 0) - borrow;
      borrow = t < 0;
      if (t < 0) t += int64_t{1} << 32;
      r.limbs[k] = static_cast<uint32_t>(t);
    }
  }
  r.trim();
  return r;
}

/// The sign of det [a 1; b 1; c 1; d 1], exactly: the 24 signed triple products of the
/// coordinates, each coordinate an integer on the grid 2^emin of the smallest among them.
int exact_det4_sign(const Vec* points[4]) {
  int emin = std::numeric_limits<int>::max();
  for (int i = 0; i < 4; ++i)
    for (double x : points[i]->v)
      if (x != 0) {
        int e = 0;
        std::frexp(x, &e);
        emin = std::min(emin, e - 53);
      }
  if (emin == std::numeric_limits<int>::max()) return 0;  // every point at the origin
  BigInt q[4][3];
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      const double x = points[i]->v[k];
      if (x == 0) continue;
      int e = 0;
      const double f = std::frexp(x, &e);  // x = f 2^e, 0.5 <= |f| < 1
      const uint64_t m = static_cast<uint64_t>(std::ldexp(std::fabs(f), 53));  // exact: 53 bits
      q[i][k] = BigInt::from(m, e - 53 - emin, x < 0);
    }
  // Cofactors along the column of ones: det4 = -det[b;c;d] + det[a;c;d] - det[a;b;d] + det[a;b;c].
  static constexpr int kRows[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
  BigInt sum;
  for (int minor = 0; minor < 4; ++minor)
    for (int p = 0; p < 6; ++p) {
      BigInt t = multiply(multiply(q[kRows[minor][0]][kPerm[p][0]], q[kRows[minor][1]][kPerm[p][1]]),
                          q[kRows[minor][2]][kPerm[p][2]]);
      // The minor's sign (- for 0 and 2) times the permutation's (the first three are even).
      if (((minor % 2 == 0) == (p < 3)) && !t.limbs.empty()) t.negative = !t.negative;
      sum = add(sum, t);
    }
  return sum.limbs.empty() ? 0 : (sum.negative ? -1 : 1);
}

/// The floating-point filter of orientation(): the sign of det [b - a; c - a; d - a] when
/// Shewchuk's error bound decides it, else 0 (undecided, or out of double's range).
int filtered_orientation(const GeneralPlane& pl, const Vec& d) {
  const double* a = pl.a.v;
  const double* b = pl.b.v;
  const double* c = pl.c.v;
  const double adx = a[0] - d.v[0], bdx = b[0] - d.v[0], cdx = c[0] - d.v[0];
  const double ady = a[1] - d.v[1], bdy = b[1] - d.v[1], cdy = c[1] - d.v[1];
  const double adz = a[2] - d.v[2], bdz = b[2] - d.v[2], cdz = c[2] - d.v[2];
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy, cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  // det [a - d; b - d; c - d] = -det [b - a; c - a; d - a].
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
  constexpr double eps = 1.1102230246251565e-16;  // 2^-53
  const double bound = 2 * (7.0 + 56.0 * eps) * eps * permanent;  // twice Shewchuk's A bound
  // The bound holds without underflow or overflow: far from both, the filter decides.
  if (permanent > 1e-250 && permanent < 1e250) {
    if (det > bound) return -1;
    if (-det > bound) return 1;
  }
  return 0;
}

/// Sign of det [b - a; c - a; d - a] (CGAL's orientation(a, b, c, d)), exactly: the filter,
/// and the exact integer determinant when it cannot decide.
int orientation(const GeneralPlane& pl, const Vec& d) {
  if (const int sign = filtered_orientation(pl, d)) return sign;
  // det [a 1; b 1; c 1; d 1] = -det [b - a; c - a; d - a].
  const Vec* points[4] = {&pl.a, &pl.b, &pl.c, &d};
  return -exact_det4_sign(points);
}

}  // namespace

/// Memory for the large arrays that every query touches at random (the visible sets, the
/// BSP): 2 MB aligned and, on Linux, marked for transparent huge pages, so that a lookup does
/// not also pay a page-table walk for each 4 KB page it lands on.
template <class T>
struct LargePages {
  using value_type = T;
  LargePages() = default;
  template <class U>
  LargePages(const LargePages<U>&) {}
  static constexpr size_t kAlign = size_t{2} << 20;
  T* allocate(size_t n) {
    if (n > std::numeric_limits<size_t>::max() / sizeof(T) - kAlign) throw std::bad_alloc();
    const size_t bytes = n * sizeof(T);
    if (bytes < kAlign) {
      void* p = std::malloc(bytes ? bytes : 1);
      if (!p) throw std::bad_alloc();
      return static_cast<T*>(p);
    }
    const size_t rounded = (bytes + kAlign - 1) / kAlign * kAlign;
    void* p = std::aligned_alloc(kAlign, rounded);
    if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(p, rounded, MADV_HUGEPAGE);  // advice only: without huge pages it still works
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t) { std::free(p); }
  template <class U>
  bool operator==(const LargePages<U>&) const { return true; }
  template <class U>
  bool operator!=(const LargePages<U>&) const { return false; }
};

struct vc_pvs {
  uint64_t fingerprint = 0;
  uint32_t object_count = 0;
  uint32_t cell_count = 0;
  std::vector<std::string> names;
  std::string rule;
  double lo[3], hi[3];
  std::vector<Node, LargePages<Node>> nodes;
  std::vector<GeneralPlane> planes;
  std::vector<uint64_t> offsets;               // per cell + 1, into ids
  std::vector<uint32_t, LargePages<uint32_t>> ids;  // every cell's visible objects, sorted per cell
  // A compact handle (vc_pvs_open_compact) keeps the hierarchy's lists coded instead of ids and
  // offsets: the format 2 coding of every node's list, where each starts (in bits), and each
  // node's parent. A cell's visible set is decoded along its path when asked for.
  bool compact = false;
  std::string coded;
  std::vector<uint32_t> node_bit;
  std::vector<int32_t> node_parent;
  // A uniform grid over the view box: per grid cell, the deepest BSP node whose subtree holds
  // the whole grid cell (slightly enlarged), where location starts instead of at the root.
  int grid_n[3] = {1, 1, 1};
  double grid_scale[3] = {0, 0, 0};
  std::vector<uint32_t> grid_start;
};

namespace {

bool finite(const Vec& p) { return std::isfinite(p.v[0]) && std::isfinite(p.v[1]) && std::isfinite(p.v[2]); }

Vec get_vec(Reader& r) {
  Vec p;
  for (double& x : p.v) x = r.get<double>();
  return p;
}

/// Planes and nodes: every inner node has a valid plane and two later children, every node
/// but the root one parent, every leaf a view cell.
void read_bsp(Reader& r, vc_pvs& f, uint64_t max_items) {
  std::vector<int32_t> leaf_cell;
  const uint64_t plane_count = r.get<uint64_t>();
  if (plane_count < 6 || plane_count > max_items) throw FileError("corrupt file: invalid plane count");
  std::vector<int32_t> axis(plane_count), general(plane_count, -1);
  std::vector<double> offset(plane_count);
  for (uint64_t i = 0; i < plane_count; ++i) {
    axis[i] = r.get<int32_t>();
    const Vec normal = get_vec(r);
    offset[i] = r.get<double>();
    GeneralPlane g{get_vec(r), get_vec(r), get_vec(r)};
    if (axis[i] < -1 || axis[i] > 2 || !finite(normal) || !std::isfinite(offset[i]))
      throw FileError("corrupt file: invalid plane");
    if (axis[i] < 0) {
      if (!finite(g.a) || !finite(g.b) || !finite(g.c)) throw FileError("corrupt file: invalid plane");
      general[i] = static_cast<int32_t>(f.planes.size());
      f.planes.push_back(g);
    }
  }
  const uint64_t count = r.get<uint64_t>();
  if (count == 0 || count > max_items || count % 2 == 0 || count >= kIndex)
    throw FileError("corrupt file: invalid node count");
  if (f.planes.size() > kIndex) throw FileError("corrupt file: invalid plane count");
  struct Raw {
    int32_t plane, child[2];
  };
  std::vector<Raw> raw(count);
  leaf_cell.resize(count);
  std::vector<int> parents(count, 0);
  for (uint64_t n = 0; n < count; ++n) {
    Raw& b = raw[n];
    b.plane = r.get<int32_t>();
    b.child[0] = r.get<int32_t>();
    b.child[1] = r.get<int32_t>();
    leaf_cell[n] = r.get<int32_t>();
    if (b.plane < 0) {
      if (b.child[0] != -1 || b.child[1] != -1)
        throw FileError("corrupt file: BSP leaf " + std::to_string(n) + " has children");
      continue;
    }
    if (static_cast<uint64_t>(b.plane) >= plane_count || leaf_cell[n] != -1)
      throw FileError("corrupt file: BSP node " + std::to_string(n) + " is invalid");
    for (int32_t ch : b.child) {
      if (ch <= static_cast<int64_t>(n) || static_cast<uint64_t>(ch) >= count)
        throw FileError("corrupt file: BSP node " + std::to_string(n) + " has a bad child");
      ++parents[ch];
    }
  }
  for (uint64_t n = 1; n < count; ++n)
    if (parents[n] != 1) throw FileError("corrupt file: BSP node " + std::to_string(n) + " is not in the tree once");
  // Preorder layout (a tree, checked above): the negative child right after its parent.
  f.nodes.reserve(count);
  std::vector<std::pair<int32_t, int64_t>> stack = {{0, -1}};  // (file node, parent's slot for `right`)
  while (!stack.empty()) {
    const auto [old, slot] = stack.back();
    stack.pop_back();
    const uint32_t me = static_cast<uint32_t>(f.nodes.size());
    if (slot >= 0) f.nodes[slot].right = me;
    Node node{};
    node.right = 0;
    const Raw& b = raw[old];
    if (b.plane < 0) {
      node.meta = static_cast<uint32_t>(leaf_cell[old]);  // checked against the cell count later
      node.list[0] = node.list[1] = 0;
      f.nodes.push_back(node);
      continue;
    }
    node.offset = offset[b.plane];
    node.meta = axis[b.plane] >= 0 ? static_cast<uint32_t>(axis[b.plane]) << 30
                                   : (3u << 30) | static_cast<uint32_t>(general[b.plane]);
    f.nodes.push_back(node);
    stack.push_back({b.child[1], me});
    stack.push_back({b.child[0], -1});  // popped next: lands at me + 1
  }
}

/// Decodes the kept lists of the hierarchy and checks them; then expands every cell's visible
/// set, or for a compact handle keeps the lists coded (format 2) with where each starts.
void read_lists(Reader& r, vc_pvs& f, uint64_t max_items, uint32_t version) {
  f.cell_count = r.get<uint32_t>();
  const std::vector<int32_t> parent = r.get_array<int32_t>(max_items);
  const std::vector<uint32_t> mht = r.get_array<uint32_t>(max_items);
  const std::string lists = r.get_string();
  if (!r.at_end()) throw FileError("corrupt file: trailing bytes");
  const size_t total = parent.size();
  if (f.cell_count == 0 || f.cell_count > total || mht.size() != f.cell_count)
    throw FileError("corrupt file: invalid view cell count");
  for (size_t n = 0; n < total; ++n)
    if (parent[n] != -1 && (parent[n] <= static_cast<int64_t>(n) || static_cast<size_t>(parent[n]) >= total))
      throw FileError("corrupt file: hierarchy node " + std::to_string(n) + " has a bad parent");
  std::vector<std::vector<uint32_t>> stored(total);
  if (version == 1) {  // LEB128 varints of the differences
    Reader lr(lists);
    for (auto& ids : stored) {
      const uint32_t n = lr.get_varint();
      if (n > f.object_count) throw FileError("corrupt file: a list holds more entries than there are objects");
      ids.resize(n);
      uint64_t previous = 0;
      for (uint32_t i = 0; i < n; ++i) {
        const uint64_t id = (i ? previous + 1 : 0) + lr.get_varint();
        if (id >= f.object_count) throw FileError("corrupt file: object id out of range");
        ids[i] = static_cast<uint32_t>(id);
        previous = id;
      }
    }
    if (!lr.at_end()) throw FileError("corrupt file: trailing bytes after the PVS lists");
  } else {  // binary interpolative coding (id_lists.h)
    if (f.compact && 8 * static_cast<uint64_t>(lists.size()) > std::numeric_limits<uint32_t>::max())
      throw FileError("the coded lists exceed 2^32 bits, more than a compact handle indexes");
    viewcells::id_lists::BitReader lr(lists.data(), lists.size());
    for (size_t n = 0; n < total; ++n) {
      if (f.compact) f.node_bit.push_back(static_cast<uint32_t>(lr.position()));
      if (!viewcells::id_lists::get_list(lr, f.object_count, stored[n]))
        throw FileError("corrupt file: malformed PVS list of hierarchy node " + std::to_string(n));
    }
    if (!lr.at_end()) throw FileError("corrupt file: trailing bytes after the PVS lists");
    if (f.compact) f.coded = lists;
  }
  if (f.compact) {
    // Format 1's lists coded as format 2's; each cell's path checked for repeats one cell at a
    // time; only the coding is kept.
    if (version == 1) {
      viewcells::id_lists::BitWriter w;
      f.node_bit.reserve(total);
      for (const auto& ids : stored) {
        if (w.bits() > std::numeric_limits<uint32_t>::max())
          throw FileError("the coded lists exceed 2^32 bits, more than a compact handle indexes");
        f.node_bit.push_back(static_cast<uint32_t>(w.bits()));
        viewcells::id_lists::put_list(w, ids.data(), ids.size(), f.object_count);
      }
      f.coded = w.finish();
    }
    f.node_parent = parent;
    std::vector<uint32_t> cell;
    for (uint32_t c = 0; c < f.cell_count; ++c) {
      cell.clear();
      for (int32_t n = static_cast<int32_t>(c); n >= 0; n = parent[n]) {
        if (cell.size() + stored[n].size() > f.object_count)
          throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
        cell.insert(cell.end(), stored[n].begin(), stored[n].end());
      }
      std::sort(cell.begin(), cell.end());
      if (std::adjacent_find(cell.begin(), cell.end()) != cell.end())
        throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
    }
    return;
  }
  // Size first: a path may not repeat an object, so a cell holds at most object_count.
  uint64_t expanded = 0;
  for (uint32_t c = 0; c < f.cell_count; ++c) {
    uint64_t here = 0;
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = parent[n]) here += stored[n].size();
    if (here > f.object_count) throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
    expanded += here;
  }
  if (expanded > (uint64_t{1} << 31))
    throw FileError("the expanded visible sets hold " + std::to_string(expanded) + " entries, more than 2^31");
  f.offsets.reserve(f.cell_count + 1);
  f.ids.reserve(expanded);
  f.offsets.push_back(0);
  for (uint32_t c = 0; c < f.cell_count; ++c) {
    const size_t first = f.ids.size();
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = parent[n])
      f.ids.insert(f.ids.end(), stored[n].begin(), stored[n].end());
    std::sort(f.ids.begin() + first, f.ids.end());
    if (std::adjacent_find(f.ids.begin() + first, f.ids.end()) != f.ids.end())
      throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
    f.offsets.push_back(f.ids.size());
  }
}

/// The deepest node whose subtree holds the whole box [lo, hi]: below it, every point of the
/// box takes the same branch at every node (a plane's side is linear in the point, so the
/// corners decide: all on the negative side or on the plane, or all strictly positive).
uint32_t deepest_node(const vc_pvs& f, const double lo[3], const double hi[3]) {
  uint32_t n = 0;
  while (f.nodes[n].right) {
    const Node& node = f.nodes[n];
    const uint32_t axis = node.meta >> 30;
    bool all_neg = true, all_pos = true;
    if (axis < 3) {
      all_neg = hi[axis] <= node.offset;
      all_pos = lo[axis] > node.offset;
    } else {
      // The filter alone: a corner it cannot decide stops the descent (the grid only needs to
      // be right where it descends, and exact signs of a grid of corners could be slow).
      for (int c = 0; c < 8 && (all_neg || all_pos); ++c) {
        const Vec corner{{(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]}};
        const int side = filtered_orientation(f.planes[node.meta & kIndex], corner);
        all_neg &= side < 0;
        all_pos &= side > 0;
      }
    }
    if (!all_neg && !all_pos) break;
    n = all_pos ? node.right : n + 1;
  }
  return n;
}

/// About two grid cells per BSP node, cubes as near as the box allows, at most 2^21 in all. A
/// box whose extent or grid scale is not a finite, positive double on some axis (a span of
/// 1e-310, or of 2e308, which overflows) gets one grid cell: location then starts at the root,
/// which is right for any box, since the grid is only a shortcut.
void build_grid(vc_pvs& f) {
  double extent[3], volume = 1;
  bool usable = true;
  for (int k = 0; k < 3; ++k) {
    volume *= extent[k] = f.hi[k] - f.lo[k];
    usable &= std::isfinite(extent[k]) && extent[k] > 0 && std::isfinite(1.0 / extent[k]);
  }
  const double target = std::min<double>(2.0 * f.nodes.size(), 1 << 21);
  const double side = std::cbrt(volume / target);
  usable &= std::isfinite(volume) && side > 0 && std::isfinite(side);
  size_t total = 1;
  for (int k = 0; k < 3; ++k) {
    const double n = usable ? std::ceil(extent[k] / side) : 1.0;
    f.grid_n[k] = static_cast<int>(std::clamp(std::isfinite(n) ? n : 1.0, 1.0, 256.0));
    f.grid_scale[k] = usable ? f.grid_n[k] / extent[k] : 0.0;
    total *= static_cast<size_t>(f.grid_n[k]);
  }
  if (!usable) {
    f.grid_start.assign(1, 0);
    return;
  }
  f.grid_start.resize(total);
  // Each grid cell enlarged by far more than the rounding of a point's grid index, so that a
  // point given to a cell lies in its enlarged box.
  double margin[3];
  for (int k = 0; k < 3; ++k) margin[k] = 1e-9 * (std::fabs(f.lo[k]) + std::fabs(f.hi[k]) + extent[k]);
  size_t at = 0;
  for (int z = 0; z < f.grid_n[2]; ++z)
    for (int y = 0; y < f.grid_n[1]; ++y)
      for (int x = 0; x < f.grid_n[0]; ++x) {
        const int i[3] = {x, y, z};
        double lo[3], hi[3];
        // extent * (i / n), not extent * i / n: the product overflows for a span near 1e308
        // (a fuzzed file: its grid cells became [inf, inf] and sent location the wrong way).
        for (int k = 0; k < 3; ++k) {
          lo[k] = f.lo[k] + extent[k] * (static_cast<double>(i[k]) / f.grid_n[k]) - margin[k];
          hi[k] = f.lo[k] + extent[k] * (static_cast<double>(i[k] + 1) / f.grid_n[k]) + margin[k];
        }
        f.grid_start[at++] = deepest_node(f, lo, hi);
      }
}

void read_file(const std::string& path, vc_pvs& f) {
  uint32_t version = 0;
  const std::string payload = read_container(path, version);
  Reader r(payload);
  const uint64_t max_items = payload.size();
  f.fingerprint = r.get<uint64_t>();
  f.object_count = r.get<uint32_t>();
  const uint64_t names = r.get<uint64_t>();
  if (names != 0 && names != f.object_count) throw FileError("corrupt file: object names do not match the object count");
  for (uint64_t i = 0; i < names; ++i) f.names.push_back(r.get_string());
  f.rule = r.get_string();
  for (double& x : f.lo) x = r.get<double>();
  for (double& x : f.hi) x = r.get<double>();
  // As the toolkit checks it (Box3::volume): finite corners and a positive volume in double.
  bool box_ok = true;
  double volume = 1;
  for (int k = 0; k < 3; ++k) {
    box_ok &= std::isfinite(f.lo[k]) && std::isfinite(f.hi[k]) && f.lo[k] <= f.hi[k];
    volume *= f.hi[k] - f.lo[k];
  }
  if (!box_ok || !(volume > 0)) throw FileError("corrupt file: invalid view box");
  read_bsp(r, f, max_items);
  read_lists(r, f, max_items, version);
  for (Node& n : f.nodes) {
    if (n.right != 0) continue;
    if (n.meta >= f.cell_count) throw FileError("corrupt file: a BSP leaf has no view cell");
    if (f.compact) continue;  // no expanded lists to point at
    n.list[0] = static_cast<uint32_t>(f.offsets[n.meta]);
    n.list[1] = static_cast<uint32_t>(f.offsets[n.meta + 1] - f.offsets[n.meta]);
  }
  build_grid(f);
}

void put_error(char* error, size_t size, const std::string& text) {
  if (!error || size == 0) return;
  std::snprintf(error, size, "%s", text.c_str());
}

}  // namespace

extern "C" {

namespace {

int open_handle(const char* path, vc_pvs** out, char* error, size_t error_size, bool compact) {
  if (out) *out = nullptr;
  if (!path || !out) {
    put_error(error, error_size, "vc_pvs_open: path and out must not be NULL");
    return 1;
  }
  vc_pvs* f = nullptr;
  try {
    f = new vc_pvs;
    f->compact = compact;
    read_file(path, *f);
  } catch (const FileError& e) {
    delete f;
    put_error(error, error_size, std::string(path) + ": " + e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    delete f;
    put_error(error, error_size, std::string(path) + ": out of memory");
    return 3;
  } catch (const std::exception& e) {
    delete f;
    put_error(error, error_size, std::string(path) + ": " + e.what());
    return 4;
  }
  *out = f;
  return 0;
}

/// A compact handle's cell: the lists along its path decoded into `out`, sorted. The lists of a
/// path are disjoint and each sorted: they are merged through a bit row over the objects when
/// that is short next to the ids (a scan of words), else sorted.
void decode_cell(const vc_pvs* pvs, uint32_t cell, std::vector<uint32_t>& out) {
  out.clear();
  thread_local std::vector<uint32_t> part;
  for (int32_t n = static_cast<int32_t>(cell); n >= 0; n = pvs->node_parent[n]) {
    const uint32_t bit = pvs->node_bit[n];
    viewcells::id_lists::BitReader r(pvs->coded.data() + bit / 8, pvs->coded.size() - bit / 8);
    r.get(static_cast<int>(bit % 8));
    viewcells::id_lists::get_list(r, pvs->object_count, part);  // checked when the handle was opened
    out.insert(out.end(), part.begin(), part.end());
  }
  const size_t words = (static_cast<size_t>(pvs->object_count) + 63) / 64;
  if (words > 4 * out.size()) {
    std::sort(out.begin(), out.end());
    return;
  }
  thread_local std::vector<uint64_t> row;
  row.assign(words, 0);
  for (uint32_t o : out) row[o >> 6] |= uint64_t{1} << (o & 63);
  size_t k = 0;
  for (size_t w = 0; w < words; ++w)
    for (uint64_t bits = row[w]; bits; bits &= bits - 1)
      out[k++] = static_cast<uint32_t>(64 * w + static_cast<size_t>(__builtin_ctzll(bits)));
}

}  // namespace

int vc_pvs_open(const char* path, vc_pvs** out, char* error, size_t error_size) {
  return open_handle(path, out, error, error_size, false);
}

int vc_pvs_open_compact(const char* path, vc_pvs** out, char* error, size_t error_size) {
  return open_handle(path, out, error, error_size, true);
}

void vc_pvs_close(vc_pvs* pvs) { delete pvs; }

int vc_pvs_is_compact(const vc_pvs* pvs) { return pvs && pvs->compact ? 1 : 0; }

size_t vc_pvs_list_bytes(const vc_pvs* pvs) {
  if (!pvs) return 0;
  return pvs->compact ? pvs->coded.size() + pvs->node_bit.size() * sizeof(uint32_t) +
                            pvs->node_parent.size() * sizeof(int32_t)
                      : pvs->offsets.size() * sizeof(uint64_t) + pvs->ids.size() * sizeof(uint32_t);
}

uint32_t vc_pvs_cell_count(const vc_pvs* pvs) { return pvs ? pvs->cell_count : 0; }
uint32_t vc_pvs_object_count(const vc_pvs* pvs) { return pvs ? pvs->object_count : 0; }
size_t vc_pvs_row_bytes(const vc_pvs* pvs) { return pvs ? (static_cast<size_t>(pvs->object_count) + 7) / 8 : 0; }
uint64_t vc_pvs_scene_fingerprint(const vc_pvs* pvs) { return pvs ? pvs->fingerprint : 0; }
const char* vc_pvs_rule(const vc_pvs* pvs) { return pvs ? pvs->rule.c_str() : ""; }

void vc_pvs_view_box(const vc_pvs* pvs, double lo[3], double hi[3]) {
  const double none = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 3; ++k) {
    if (lo) lo[k] = pvs ? pvs->lo[k] : none;
    if (hi) hi[k] = pvs ? pvs->hi[k] : none;
  }
}

const char* vc_pvs_object_name(const vc_pvs* pvs, uint32_t object) {
  return pvs && object < pvs->names.size() ? pvs->names[object].c_str() : "";
}

size_t vc_pvs_memory_bytes(const vc_pvs* pvs) {
  if (!pvs) return 0;
  size_t n = sizeof(vc_pvs) + pvs->rule.capacity();
  for (const std::string& s : pvs->names) n += sizeof(s) + s.capacity();
  return n + pvs->nodes.capacity() * sizeof(Node) + pvs->planes.capacity() * sizeof(GeneralPlane) +
         pvs->grid_start.capacity() * sizeof(uint32_t) + pvs->offsets.capacity() * sizeof(uint64_t) +
         pvs->ids.capacity() * sizeof(uint32_t) + pvs->coded.capacity() +
         pvs->node_bit.capacity() * sizeof(uint32_t) + pvs->node_parent.capacity() * sizeof(int32_t);
}

namespace {

/// The leaf holding p, or null outside the view box (NaN coordinates included).
inline const Node* leaf_at(const vc_pvs* pvs, double x, double y, double z) {
  if (!pvs) return nullptr;
  const Vec p{{x, y, z}};
  size_t cell = 0, stride = 1;
  for (int k = 0; k < 3; ++k) {
    if (!(p.v[k] >= pvs->lo[k] && p.v[k] <= pvs->hi[k])) return nullptr;  // NaN fails too
    // Clamped in double before the conversion: an index of inf or NaN never reaches an int.
    const double t = (p.v[k] - pvs->lo[k]) * pvs->grid_scale[k];
    const int i = t > 0 ? static_cast<int>(std::min(t, static_cast<double>(pvs->grid_n[k] - 1))) : 0;
    cell += stride * static_cast<size_t>(i);
    stride *= static_cast<size_t>(pvs->grid_n[k]);
  }
  const Node* nodes = pvs->nodes.data();
  const Node* n = nodes + pvs->grid_start[cell];
  while (n->right) {
    const uint32_t axis = n->meta >> 30;
    const bool positive = axis < 3 ? p.v[axis] > n->offset : orientation(pvs->planes[n->meta & kIndex], p) > 0;
    n = positive ? nodes + n->right : n + 1;
  }
  return n;
}

}  // namespace

int32_t vc_pvs_locate(const vc_pvs* pvs, double x, double y, double z) {
  const Node* n = leaf_at(pvs, x, y, z);
  return n ? static_cast<int32_t>(n->meta) : -1;
}

int32_t vc_pvs_locate_objects(const vc_pvs* pvs, double x, double y, double z, const uint32_t** objects,
                              size_t* count) {
  const Node* n = leaf_at(pvs, x, y, z);
  const bool listed = n && !pvs->compact;  // n is null for a null handle
  if (objects) *objects = listed ? pvs->ids.data() + n->list[0] : nullptr;
  if (count) *count = listed ? n->list[1] : 0;
  return n ? static_cast<int32_t>(n->meta) : -1;
}

size_t vc_pvs_cell_objects(const vc_pvs* pvs, int32_t cell, const uint32_t** objects) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count || pvs->compact) {
    if (objects) *objects = nullptr;
    return 0;
  }
  const uint64_t first = pvs->offsets[cell], last = pvs->offsets[cell + 1];
  if (objects) *objects = pvs->ids.data() + first;
  return static_cast<size_t>(last - first);
}

size_t vc_pvs_cell_objects_copy(const vc_pvs* pvs, int32_t cell, uint32_t* objects, size_t capacity) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count) return 0;
  if (!pvs->compact) {
    const uint64_t first = pvs->offsets[cell], count = pvs->offsets[cell + 1] - first;
    if (objects) std::copy_n(pvs->ids.data() + first, std::min<uint64_t>(count, capacity), objects);
    return static_cast<size_t>(count);
  }
  thread_local std::vector<uint32_t> ids;
  decode_cell(pvs, static_cast<uint32_t>(cell), ids);
  if (objects) std::copy_n(ids.data(), std::min(ids.size(), capacity), objects);
  return ids.size();
}

int vc_pvs_cell_bits(const vc_pvs* pvs, int32_t cell, uint8_t* row, size_t row_bytes) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count || !row || row_bytes < vc_pvs_row_bytes(pvs))
    return -1;
  std::memset(row, 0, row_bytes);
  if (pvs->compact) {
    thread_local std::vector<uint32_t> ids;
    decode_cell(pvs, static_cast<uint32_t>(cell), ids);
    for (uint32_t o : ids) row[o >> 3] = static_cast<uint8_t>(row[o >> 3] | (1u << (o & 7)));
    return 0;
  }
  for (uint64_t i = pvs->offsets[cell]; i < pvs->offsets[cell + 1]; ++i)
    row[pvs->ids[i] >> 3] = static_cast<uint8_t>(row[pvs->ids[i] >> 3] | (1u << (pvs->ids[i] & 7)));
  return 0;
}

int vc_pvs_cell_sees(const vc_pvs* pvs, int32_t cell, uint32_t object) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count) return 0;
  if (pvs->compact) {
    thread_local std::vector<uint32_t> ids;
    decode_cell(pvs, static_cast<uint32_t>(cell), ids);
    return std::binary_search(ids.begin(), ids.end(), object) ? 1 : 0;
  }
  const uint32_t* first = pvs->ids.data() + pvs->offsets[cell];
  const uint32_t* last = pvs->ids.data() + pvs->offsets[cell + 1];
  return std::binary_search(first, last, object) ? 1 : 0;
}

}  // extern "C"
