#include "entries.h"

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <iterator>
#include <vector>
#include <memory>
#include <optional>
#include <sstream>
#include <string_view>

#include "support/test_scenes.h"
#include "viewcells/agvs/agvs.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/q3/bsp_file.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/bake.h"
#include "viewcells/runtime.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/scene/generators.h"

namespace viewcells::fuzz {
namespace {

std::string_view bytes_of(const uint8_t* data, size_t size) { return {reinterpret_cast<const char*>(data), size}; }

/// A scratch path in /dev/shm (or /tmp), one per process.
std::string scratch(const std::string& ext) {
  const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  return std::string(dir) + "/viewcells_fuzz_" + std::to_string(getpid()) + ext;
}

/// The input as the payload of a valid container: the first byte picks the format version
/// (1..max_version), the rest is the payload.
std::string container_file(const uint8_t* data, size_t size, const char (&magic)[5], uint32_t max_version,
                           const std::string& ext) {
  const std::string path = scratch(ext);
  const uint32_t version = size ? 1 + data[0] % max_version : 1;
  write_container(path, magic, version, std::string(bytes_of(data, size).substr(size ? 1 : 0)));
  return path;
}

template <class F>
void expecting_errors(F&& body) {
  try {
    body();
  } catch (const Error&) {
  }
}

Scene scene_of(RawMesh mesh, const char* name) { return make_scene(std::move(mesh), ObjectGrouping::kAuto, name); }

constexpr uint64_t kIdentity = 0x5eed;

struct AgvsFixture {
  Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  std::unique_ptr<RayCaster> caster = make_embree_caster(scene);
  CellLocator cells = test::kd_cells(scene, 8, 2000);
  AgvsConfig config = make_config();

  static AgvsConfig make_config() {
    AgvsConfig c;
    c.max_samples = 400;
    c.batch_size = 200;
    c.show_progress = false;
    return c;
  }
};

AgvsFixture& agvs_fixture() {
  static AgvsFixture f;
  return f;
}

}  // namespace

void entry_obj(const uint8_t* data, size_t size) {
  expecting_errors([&] {
    // Input after a line "%%MTL" is the text of every material library the OBJ names, so the
    // MTL parser and the see-through grouping are fuzzed too.
    const std::string_view bytes = bytes_of(data, size);
    const size_t split = bytes.find("\n%%MTL\n");
    const std::string obj(bytes.substr(0, split));
    const std::string mtl = split == std::string_view::npos ? std::string() : std::string(bytes.substr(split + 7));
    std::istringstream in{obj};
    scene_of(read_obj(in, "fuzz.obj", [&](const std::string&) { return mtl; }), "fuzz.obj");
  });
}
void entry_ply(const uint8_t* data, size_t size) {
  expecting_errors([&] { scene_of(read_ply(bytes_of(data, size), "fuzz.ply"), "fuzz.ply"); });
}
void entry_off(const uint8_t* data, size_t size) {
  expecting_errors([&] { scene_of(read_off(bytes_of(data, size), "fuzz.off"), "fuzz.off"); });
}
void entry_stl(const uint8_t* data, size_t size) {
  expecting_errors([&] { scene_of(read_stl(bytes_of(data, size), "fuzz.stl"), "fuzz.stl"); });
}
void entry_bsp(const uint8_t* data, size_t size) {
  expecting_errors([&] { q3_world_mesh(parse_q3bsp(std::string(bytes_of(data, size)), "fuzz.bsp")); });
}
void entry_glb(const uint8_t* data, size_t size) {
  expecting_errors([&] {
    scene_of(read_assimp_bytes(bytes_of(data, size), ".glb", AssimpObjects::kNodes, "fuzz.glb"), "fuzz.glb");
  });
}
void entry_fbx(const uint8_t* data, size_t size) {
  expecting_errors([&] {
    scene_of(read_assimp_bytes(bytes_of(data, size), ".fbx", AssimpObjects::kMeshes, "fuzz.fbx"), "fuzz.fbx");
  });
}
void entry_vseg(const uint8_t* data, size_t size) {
  expecting_errors([&] { read_segments(container_file(data, size, "VSEG", 1, ".vseg")); });
}
void entry_vcells(const uint8_t* data, size_t size) {
  expecting_errors([&] { read_subdivision(container_file(data, size, "VCEL", 3, ".vcells")); });
}
void entry_pvs(const uint8_t* data, size_t size) {
  expecting_errors([&] {
    const std::string path = container_file(data, size, "VPVS", 2, ".pvs");
    // The engines' reader (runtime/) must accept exactly what the toolkit accepts, and then
    // agree with it: the same cells and visible sets at the same points.
    vc_pvs* runtime = nullptr;
    vc_pvs* compact = nullptr;
    const bool runtime_ok = vc_pvs_open(path.c_str(), &runtime, nullptr, 0) == 0;
    std::unique_ptr<vc_pvs, void (*)(vc_pvs*)> owner(runtime, vc_pvs_close);
    const bool compact_ok = vc_pvs_open_compact(path.c_str(), &compact, nullptr, 0) == 0;
    std::unique_ptr<vc_pvs, void (*)(vc_pvs*)> compact_owner(compact, vc_pvs_close);
    if (compact_ok != runtime_ok) std::abort();
    std::optional<PvsFile> read;
    try {
      read.emplace(read_pvs(path));
    } catch (const Error&) {
      if (runtime_ok) std::abort();
      throw;
    }
    if (!runtime_ok) std::abort();
    const PvsFile& f = *read;
    // Point location walks the BSP read from the file: a corrupt tree must not loop or run off.
    for (const Vec3& p : {f.bsp.view_box.center(), f.bsp.view_box.lo, f.bsp.view_box.hi}) {
      const int32_t cell = f.locate(p);
      if (vc_pvs_locate(runtime, p.x, p.y, p.z) != cell) std::abort();
      const uint32_t* ids = nullptr;
      const size_t n = vc_pvs_cell_objects(runtime, cell, &ids);
      if (cell >= 0 && std::vector<uint32_t>(ids, ids + n) != f.pvs.cell_pvs(static_cast<uint32_t>(cell))) std::abort();
      std::vector<uint32_t> copied(f.object_count);
      copied.resize(vc_pvs_cell_objects_copy(compact, cell, copied.data(), copied.size()));
      if (cell >= 0 && copied != f.pvs.cell_pvs(static_cast<uint32_t>(cell))) std::abort();
    }
  });
}
void entry_runtime(const uint8_t* data, size_t size) {
  // Byte 0 picks the format version; bytes 1-48 are two query points as raw doubles (any bit
  // pattern: NaN, infinities, denormals); the rest is the payload, in a valid container.
  constexpr size_t kPoints = 48;
  double raw[6] = {0, 0, 0, 0, 0, 0};
  if (size > kPoints) std::memcpy(raw, data + 1, kPoints);
  std::string input(bytes_of(data, size));
  if (size > kPoints) input.erase(1, kPoints);
  const std::string path = container_file(reinterpret_cast<const uint8_t*>(input.data()), input.size(), "VPVS", 2,
                                          ".pvs");
  vc_pvs* full = nullptr;
  vc_pvs* compact = nullptr;
  const bool full_ok = vc_pvs_open(path.c_str(), &full, nullptr, 0) == 0;
  std::unique_ptr<vc_pvs, void (*)(vc_pvs*)> full_owner(full, vc_pvs_close);
  const bool compact_ok = vc_pvs_open_compact(path.c_str(), &compact, nullptr, 0) == 0;
  std::unique_ptr<vc_pvs, void (*)(vc_pvs*)> compact_owner(compact, vc_pvs_close);
  if (full_ok != compact_ok || full_ok != (full != nullptr)) std::abort();
  std::optional<PvsFile> read;
  try {
    read.emplace(read_pvs(path));
  } catch (const Error&) {
  }
  if (read.has_value() != full_ok) std::abort();  // the runtime opens exactly what the toolkit reads
  // Every call, also on the handle that may be NULL: defined for every argument.
  for (vc_pvs* h : {full, compact}) {
    double lo[3], hi[3];
    vc_pvs_view_box(h, lo, hi);
    std::vector<Vec3> points = {{raw[0], raw[1], raw[2]}, {raw[3], raw[4], raw[5]}, {lo[0], lo[1], lo[2]},
                                {hi[0], hi[1], hi[2]},    {0.5 * lo[0] + 0.5 * hi[0], 0.5 * lo[1] + 0.5 * hi[1], 0.5 * lo[2] + 0.5 * hi[2]},
                                {lo[0], raw[1], hi[2]}};
    const uint32_t cells = vc_pvs_cell_count(h), objects = vc_pvs_object_count(h);
    std::vector<uint32_t> ids(objects);
    std::vector<uint8_t> row(vc_pvs_row_bytes(h));
    for (const Vec3& p : points) {
      const int32_t cell = vc_pvs_locate(h, p.x, p.y, p.z);
      if (cell < -1 || (cell >= 0 && static_cast<uint32_t>(cell) >= cells)) std::abort();
      if (read && cell != (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) ? read->locate(p) : -1))
        std::abort();
      const uint32_t* list = nullptr;
      size_t count = 0;
      if (vc_pvs_locate_objects(h, p.x, p.y, p.z, &list, &count) != cell) std::abort();
      const size_t copied = vc_pvs_cell_objects_copy(h, cell, ids.data(), ids.size());
      if (cell >= 0 && std::vector<uint32_t>(ids.begin(), ids.begin() + copied) != read->pvs.cell_pvs(cell))
        std::abort();
      vc_pvs_cell_bits(h, cell, row.data(), row.size());
      vc_pvs_cell_sees(h, cell, size > 2 ? data[2] : 0);
    }
    const int32_t some = static_cast<int32_t>(size > 1 ? data[size - 1] : 0) - 1;  // -1 and a few cells
    vc_pvs_cell_objects(h, some, nullptr);
    vc_pvs_object_name(h, static_cast<uint32_t>(some));
    vc_pvs_rule(h);
    vc_pvs_memory_bytes(h);
    vc_pvs_list_bytes(h);
  }
}
void entry_vagvs(const uint8_t* data, size_t size) {
  AgvsFixture& f = agvs_fixture();
  const std::string path = container_file(data, size, "VAGS", 4, ".vagvs");
  expecting_errors([&] {
    AgvsSolver solver(f.scene, *f.caster, f.cells, f.config);
    solver.load(path, kIdentity);
    solver.set_limits(solver.stats().samples + 400, 0, 0);
    solver.run();
  });
}

void write_vagvs_seed(const std::string& path) {
  AgvsFixture& f = agvs_fixture();
  AgvsSolver solver(f.scene, *f.caster, f.cells, f.config);
  solver.run();
  solver.save(path, kIdentity);
}

void entry_bake(const uint8_t* data, size_t size) {
  // The in-memory C API end to end (issue 67). Byte 0: objects (1 to 4). Per object: vertex
  // count, triangle count (0 to 15 each) and a see-through flag; then three bytes per vertex
  // (grid coordinates 0 to 15, or, from 250 up, NaN, infinities, 1e300, -0), three per
  // triangle (vertex indices, possibly out of range); the rest picks option words from a
  // dictionary of cheap ones (so that a run stays short) after a small base bake. Whatever
  // vc_bake accepts must give a file the runtime opens with exactly that many objects (ids are
  // positions). The input's bytes also go to vc_pvs_open_memory as they are.
  size_t at = 0;
  auto next = [&]() -> uint8_t { return at < size ? data[at++] : 0; };
  const size_t n = 1 + next() % 4;
  std::vector<std::vector<double>> vertices(n);
  std::vector<std::vector<uint32_t>> indices(n);
  std::vector<int> see_through(n);
  std::vector<std::string> names(n);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t v = next() % 16, t = next() % 16;
    see_through[i] = next() & 1;
    names[i] = "o" + std::to_string(i);
    for (uint32_t k = 0; k < 3 * v; ++k) {
      const uint8_t b = next();
      const double special[] = {std::nan(""), INFINITY, -INFINITY, 1e300, -0.0, 0.5};
      vertices[i].push_back(b >= 250 ? special[b - 250] : static_cast<double>(b % 16));
    }
    for (uint32_t k = 0; k < 3 * t; ++k) indices[i].push_back(next() % 20);
  }
  static const char* const kWords[] = {"--seed", "7", "--no-ga", "--prove-hidden", "--conservative", "--cells", "3", "0",
                                       "-1", "99999999999999999999", "nan", "x", "--memory", "1K", "--time", "0.5",
                                       "--aimed-rays", "8", "--view-box", "0,0,0,1,1,1", "--samples", "--max-cells",
                                       "--near-samples", "--objects", "groups", "--report", "-o", "--help", "--holes",
                                       "50%", "", "--pixel-error", "1e-300"};
  std::vector<std::string> words = {"--cells", "2", "--samples", "500", "--agvs-samples", "500", "--near-samples", "0",
                                    "--max-cells", "8"};
  while (at < size && words.size() < 24) words.push_back(kWords[next() % std::size(kWords)]);
  std::vector<const char*> options;
  for (const std::string& w : words) options.push_back(w.c_str());
  options.push_back(nullptr);
  std::vector<vc_bake_object> objects;
  for (size_t i = 0; i < n; ++i)
    objects.push_back({names[i].c_str(), vertices[i].data(), static_cast<uint32_t>(vertices[i].size() / 3),
                       indices[i].data(), static_cast<uint32_t>(indices[i].size() / 3), see_through[i]});
  vc_bake_result* result = nullptr;
  char error[256] = "";
  const int code = vc_bake(objects.data(), objects.size(), options.data(), nullptr, nullptr, nullptr, &result, error,
                           sizeof error);
  if ((code == 0) != (result != nullptr) || code < 0 || code > 3 || (code != 0 && error[0] == '\0')) std::abort();
  if (result) {
    size_t bytes = 0;
    const void* image = vc_bake_result_bytes(result, &bytes);
    vc_pvs* p = nullptr;
    if (vc_pvs_open_memory(image, bytes, 0, &p, nullptr, 0) != 0) std::abort();  // what it wrote must open
    if (vc_pvs_object_count(p) != n) std::abort();                                 // ids are positions
    vc_pvs_close(p);
    vc_bake_result_free(result);
  }
  for (int compact : {0, 1}) {
    vc_pvs* p = nullptr;
    if (vc_pvs_open_memory(data, size, compact, &p, nullptr, 0) == 0) {
      (void)vc_pvs_locate(p, 0.5, 0.5, 0.5);
      vc_pvs_close(p);
    }
  }
}

}  // namespace viewcells::fuzz
