// The Python module `viewcells`: bake view cells and their PVSs from Python, with a scene from
// numpy arrays (an editor's meshes) or from a file, and read the result back as arrays.
//
//   import viewcells, numpy as np
//   scene = viewcells.Scene(vertices, triangles, objects=ids, names=names, see_through=flags)
//   baked = viewcells.bake(scene, "level.pvs", cells=100, pixel_error=5, progress=print)
//   baked.query((3, 12, 1.5)), baked.pvs(cell), baked.cell_bounds, baked.report
//
// bake() takes the bake's options as keywords (cells=100 is --cells 100, no_ga=True is
// --no-ga), set through the library's table of options (pipeline/options.h), the one the
// command line is built from, so its defaults, checks and help are exactly `viewcells bake`'s;
// the scene then comes from memory (pipeline::SceneSource::scene) when it is a Scene. Errors
// are viewcells.Error carrying the library's message, with options named as keywords.
// Type errors name the argument and the type given, not only "Unable to cast".
#define PYBIND11_DETAILED_ERROR_MESSAGES
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <iterator>
#include <mutex>
#include <thread>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viewcells/cells/view_cells.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/paths.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/options.h"
#include "viewcells/pipeline/play.h"
#include "viewcells/q3/bsp_file.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/vis/level_view.h"
#include "viewcells/scene/scene.h"

namespace py = pybind11;
using namespace viewcells;

namespace {

/// A scene from arrays: vertices (N x 3, float64), triangles (M x 3, integer indices), per
/// triangle its object (M; default: one object), object names, and which objects are seen
/// through (glass, water: in PVSs, hiding nothing).
using Indices = py::array_t<int64_t, py::array::c_style | py::array::forcecast>;

/// An array of indices as int64, refusing values a cast would change (2.9, NaN, 1e30): numpy
/// would truncate them silently.
Indices whole_numbers(const py::object& values, const std::string& scene, const std::string& what) {
  py::array a = py::array::ensure(values);
  if (!a) throw Error(scene, 0, what + " must be an array of integers");
  const char kind = a.dtype().kind();
  if (kind == 'f') {
    const py::array_t<double, py::array::c_style | py::array::forcecast> d(a);
    const double* v = d.data();
    for (py::ssize_t i = 0; i < d.size(); ++i)
      if (!(v[i] == std::floor(v[i]) && std::abs(v[i]) < 9.0e15))
        throw Error(scene, 0, what + " must be whole numbers: entry " + std::to_string(i) + " is " + py::str(py::float_(v[i])).cast<std::string>());
  } else if (kind != 'i' && kind != 'u' && kind != 'b') {
    throw Error(scene, 0, what + " must be an array of integers, not of dtype " + py::str(a.dtype()).cast<std::string>());
  }
  return Indices(a);
}

std::shared_ptr<const Scene> scene_from_arrays(py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
                                               const py::object& triangle_values, const py::object& object_values,
                                               std::optional<std::vector<std::string>> names,
                                               std::optional<std::vector<bool>> see_through, const std::string& name) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw Error(name, 0, "vertices must be an array of shape (N, 3)");
  const Indices triangles = whole_numbers(triangle_values, name, "triangles");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3) throw Error(name, 0, "triangles must be an array of shape (M, 3)");
  std::optional<Indices> objects;
  if (!object_values.is_none()) objects = whole_numbers(object_values, name, "objects");
  RawMesh mesh;
  const auto v = vertices.unchecked<2>();
  for (py::ssize_t i = 0; i < v.shape(0); ++i) {
    mesh.vertices.push_back({v(i, 0), v(i, 1), v(i, 2)});
    if (!is_finite(mesh.vertices.back()))
      throw Error(name, 0, "vertex " + std::to_string(i) + " (counting from 0) has a NaN or infinite coordinate");
  }
  const auto t = triangles.unchecked<2>();
  for (py::ssize_t i = 0; i < t.shape(0); ++i) {
    std::array<uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      if (t(i, k) < 0 || t(i, k) >= v.shape(0))
        throw Error(name, 0, "triangle " + std::to_string(i) + " (counting from 0) has vertex index " +
                                 std::to_string(t(i, k)) + ", not from 0 to " + std::to_string(v.shape(0) - 1));
      tri[k] = static_cast<uint32_t>(t(i, k));
    }
    mesh.triangles.push_back(tri);
  }
  int64_t groups = 1;
  if (objects) {
    if (objects->ndim() != 1 || objects->shape(0) != t.shape(0))
      throw Error(name, 0, "objects must give one object id per triangle");
    const auto o = objects->unchecked<1>();
    for (py::ssize_t i = 0; i < o.shape(0); ++i) {
      // Ids are kept (every id below the largest is an object): bounded so that a stray large
      // id cannot ask for billions of objects.
      if (o(i) < 0 || o(i) >= (int64_t{1} << 24))
        throw Error(name, 0, "objects: entry " + std::to_string(i) + " is " + std::to_string(o(i)) +
                                 "; object ids must be from 0 to 2^24 - 1 (16777215)");
      mesh.triangle_group.push_back(static_cast<uint32_t>(o(i)));
      groups = std::max(groups, o(i) + 1);
    }
  } else {
    mesh.triangle_group.assign(mesh.triangles.size(), 0);
  }
  if (names && static_cast<int64_t>(names->size()) != groups)
    throw Error(name, 0, "names must name every object (" + std::to_string(groups) + ")");
  for (int64_t g = 0; g < groups; ++g)
    mesh.group_names.push_back(names ? (*names)[g] : "object" + std::to_string(g));
  if (see_through) {
    if (static_cast<int64_t>(see_through->size()) != groups)
      throw Error(name, 0, "see_through must give a flag for every object (" + std::to_string(groups) + ")");
    for (bool s : *see_through) mesh.group_occluder.push_back(s ? 0 : 1);
  }
  mesh.keep_group_ids = true;  // the PVSs list the caller's object ids, also past an empty one
  return std::make_shared<const Scene>(make_scene(std::move(mesh), ObjectGrouping::kGroups, name));
}

/// A keyword argument as the text of its option: True/False for a flag ("true" given to an
/// option that wants a number is refused by name), a list or tuple joined by commas (a box, an
/// eye band), and for a repeatable option (start) one text per item.
std::vector<std::string> option_texts(const pipeline::BakeOption& option, const std::string& key, const py::handle& value) {
  auto one = [](const py::handle& v) -> std::string {
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
      std::string joined;
      for (const py::handle& item : v) joined += (joined.empty() ? "" : ",") + py::str(item).cast<std::string>();
      return joined;
    }
    return py::str(v);
  };
  const bool sequence = py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value);
  if (option.kind == pipeline::BakeOption::Kind::kTexts && sequence) {
    bool nested = false;
    for (const py::handle& item : value)
      nested |= py::isinstance<py::list>(item) || py::isinstance<py::tuple>(item) || py::isinstance<py::str>(item);
    if (nested) {
      std::vector<std::string> texts;
      for (const py::handle& item : value) texts.push_back(one(item));
      return texts;
    }
  }
  if (sequence && option.kind != pipeline::BakeOption::Kind::kText && option.kind != pipeline::BakeOption::Kind::kTexts)
    throw Error("bake: " + key + " (keyword) takes one value, not a list");
  return {one(value)};
}

/// The options as keywords, for help: "  max_cells=INT in [1, 10000000]  Elementary cells ...".
std::string keyword_listing() {
  std::string out, heading;
  for (const pipeline::BakeOption& o : pipeline::bake_option_table()) {
    if (o.group != heading) out += "\n" + (heading = o.group) + ":\n";
    out += "  " + o.keyword + "=" + (o.kind == pipeline::BakeOption::Kind::kFlag ? std::string("True|False")
                                                                  : o.type.empty() ? std::string("TEXT") : o.type) +
           "\n      " + o.help + "\n";
  }
  return out;
}

/// A library message with every option of the bake named as Python names it: "--max-cells" ->
/// "max_cells (keyword)", "--no-prove-hidden" -> "prove_hidden=False (keyword)".
std::string as_keywords(const std::string& message) {
  std::vector<std::pair<std::string, std::string>> names;
  for (const pipeline::BakeOption& o : pipeline::bake_option_table()) {
    names.push_back({o.flag, o.keyword + " (keyword)"});
    if (!o.negation.empty()) names.push_back({o.negation, o.keyword + "=False (keyword)"});
  }
  return pipeline::rename_options(message, std::move(names));
}

/// A path given as str or os.PathLike (pathlib.Path); TypeError otherwise.
std::string path_of(const py::handle& value, const char* what) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::hasattr(value, "__fspath__")) {
    const py::object p = py::module_::import("os").attr("fspath")(value);
    if (py::isinstance<py::str>(p)) return p.cast<std::string>();
  }
  throw py::type_error(std::string(what) + " must be a path (str or os.PathLike), not " +
                       py::str(py::type::of(value).attr("__name__")).cast<std::string>());
}

/// A .pvs file read back: the view cells (their point location, bounds, convex pieces and
/// PVSs), the merge history above them (coarser cuts), the report of the bake that wrote it as
/// a dict, and, when the scene is known, the cells as meshes with their render costs.
struct Baked {
  std::string path;
  PvsFile file;
  std::unique_ptr<CellLocator> cells;
  py::dict report;
  std::shared_ptr<const Scene> scene;  ///< null until known
  std::optional<pipeline::SceneSource> scene_file;  ///< read when `scene` is first needed
  CostModel model;
  std::vector<std::vector<int32_t>> leaves_of;         ///< per view cell, its BSP leaves (lazily)
  std::vector<ConvexPolyhedron> leaf_poly;             ///< per BSP node (leaves filled, lazily)
  std::optional<LevelView> level;                      ///< with a scene (lazily)

  Baked(std::string p, std::shared_ptr<const Scene> s, const CostModel& m)
      : Baked(p, read_pvs(p), std::move(s), m) {}
  /// The file's content already in memory (what the bake just wrote), not read again.
  Baked(std::string p, PvsFile f, std::shared_ptr<const Scene> s, const CostModel& m)
      : path(std::move(p)), file(std::move(f)), scene(std::move(s)), model(m) {
    cells = std::make_unique<CellLocator>(file.bsp, file.leaf_cell, file.pvs.cell_count);
    if (scene && scene->fingerprint() != file.scene_fingerprint)
      throw Error(scene->source, 0, "is not the scene " + path + " was baked from (fingerprints differ)");
  }

  uint32_t cell_index(int64_t cell) const {
    if (cell < 0 || cell >= file.pvs.cell_count) throw Error(path, 0, "no view cell " + std::to_string(cell));
    return static_cast<uint32_t>(cell);
  }
  int32_t query(const std::array<double, 3>& p) const {
    const Vec3 q{p[0], p[1], p[2]};
    return cells->cell_at(q);
  }
  py::array_t<uint32_t> pvs(int64_t cell) const {
    const std::vector<uint32_t> ids = file.pvs.cell_pvs(cell_index(cell));
    return py::array_t<uint32_t>(static_cast<py::ssize_t>(ids.size()), ids.data());
  }
  py::array_t<double> bounds() const {
    py::array_t<double> out({static_cast<py::ssize_t>(file.pvs.cell_count), py::ssize_t{2}, py::ssize_t{3}});
    auto o = out.mutable_unchecked<3>();
    for (uint32_t c = 0; c < file.pvs.cell_count; ++c) {
      const Box3& b = cells->cell_bounds(c);
      for (int k = 0; k < 3; ++k) {
        o(c, 0, k) = b.lo[k];
        o(c, 1, k) = b.hi[k];
      }
    }
    return out;
  }

  /// A view cell is the union of BSP leaves, each convex: its pieces as (vertices (V, 3), faces:
  /// vertex lists counter-clockwise seen from outside), found by clipping the view box down the
  /// tree as the viewers do (a .pvs keeps the tree, not the split order).
  py::list polyhedra(int64_t cell) {
    const uint32_t c = cell_index(cell);
    if (leaves_of.empty()) {
      leaves_of.resize(file.pvs.cell_count);
      leaf_poly.resize(file.bsp.nodes.size());
      clip_to_leaves(file.bsp, ConvexPolyhedron::box(file.bsp.view_box, 0),
                     [&](int32_t leaf, const ConvexPolyhedron& part) {
                       const int32_t in = file.leaf_cell[leaf];
                       if (in < 0 || static_cast<uint32_t>(in) >= file.pvs.cell_count) return;
                       leaf_poly[leaf] = part;
                       leaves_of[in].push_back(leaf);
                     });
    }
    py::list out;
    for (int32_t leaf : leaves_of[c]) {
      const ConvexPolyhedron& poly = leaf_poly[leaf];
      py::array_t<double> v({static_cast<py::ssize_t>(poly.vertices().size()), py::ssize_t{3}});
      auto w = v.mutable_unchecked<2>();
      for (size_t i = 0; i < poly.vertices().size(); ++i)
        for (int k = 0; k < 3; ++k) w(i, k) = poly.vertices()[i][k];
      py::list faces;
      for (const PolyFace& f : poly.faces()) faces.append(py::cast(f.vertices));
      out.append(py::make_tuple(v, faces));
    }
    return out;
  }

  /// The coarser view cells of the merge history above the file's: `count` groups (1 to the
  /// cell count), cut where the history has exactly that many. Returns each cell's group and
  /// each group's PVS (the union of its cells', which the hierarchy node keeps whole).
  py::tuple cut(int64_t count) const {
    const uint32_t n = file.pvs.cell_count;
    const PvsHierarchy& h = file.pvs;
    size_t roots = 0;
    for (size_t i = 0; i < h.node_count(); ++i) roots += h.parent[i] < 0;
    if (count < static_cast<int64_t>(roots) || count > n)
      throw Error(path, 0, "the merge history above the " + std::to_string(n) + " view cells cuts from " +
                               std::to_string(roots) + " to " + std::to_string(n) + " cells, not " +
                               std::to_string(count));
    // The merges happened in node order (a parent after its children), each joining two: the
    // cut of `count` groups is what the first n - count merges made, every node among the first
    // n + (n - count) whose parent is not among them.
    const size_t kept = 2 * static_cast<size_t>(n) - static_cast<size_t>(count);
    std::vector<int32_t> group_of_node(kept, -1);
    std::vector<int32_t> groups;
    for (size_t i = 0; i < kept; ++i)
      if (h.parent[i] < 0 || static_cast<size_t>(h.parent[i]) >= kept) {
        group_of_node[i] = static_cast<int32_t>(groups.size());
        groups.push_back(static_cast<int32_t>(i));
      }
    for (size_t i = kept; i-- > 0;)  // parents come after children: go down from the top
      if (group_of_node[i] < 0) group_of_node[i] = group_of_node[h.parent[i]];
    py::array_t<int32_t> cell_group(static_cast<py::ssize_t>(n));
    auto g = cell_group.mutable_unchecked<1>();
    std::vector<std::vector<uint32_t>> lists(groups.size());
    for (uint32_t c = 0; c < n; ++c) {
      g(c) = group_of_node[c];
      std::vector<uint32_t> merged;
      const std::vector<uint32_t> mine = h.cell_pvs(c);
      auto& into = lists[g(c)];
      std::set_union(into.begin(), into.end(), mine.begin(), mine.end(), std::back_inserter(merged));
      into.swap(merged);
    }
    py::list pvs;
    for (const auto& l : lists) pvs.append(py::array_t<uint32_t>(static_cast<py::ssize_t>(l.size()), l.data()));
    return py::make_tuple(cell_group, pvs);
  }

  const LevelView& level_view() {
    if (!scene && scene_file) {
      scene = std::shared_ptr<const Scene>(pipeline::load_scene_for_rays(*scene_file, [](const std::string&) {}).scene.release());
      if (scene->fingerprint() != file.scene_fingerprint)
        throw Error(scene->source, 0, "is not the scene " + path + " was baked from (fingerprints differ)");
    }
    if (!scene)
      throw Error(path, 0, "needs the scene it was baked from: viewcells.read(path, scene) or a bake of a Scene");
    if (!level) level = make_level_view(file, *scene, model);
    return *level;
  }
  /// Per view cell, its leaves as one mesh (each leaf shrunk a little towards its centre, as
  /// the viewers draw them): (vertices (V, 3) float32, triangles (T, 3)).
  py::list meshes() {
    const GroupedMesh& m = level_view().cells;
    py::list out;
    for (size_t c = 0; c < m.group_count(); ++c) {
      const uint32_t v0 = m.first_vertex[c], v1 = m.first_vertex[c + 1];
      const uint32_t i0 = m.first_index[c], i1 = m.first_index[c + 1];
      py::array_t<float> v({static_cast<py::ssize_t>(v1 - v0), py::ssize_t{3}});
      std::copy(m.positions.begin() + 3 * v0, m.positions.begin() + 3 * v1, v.mutable_data());
      py::array_t<uint32_t> t({static_cast<py::ssize_t>((i1 - i0) / 3), py::ssize_t{3}});
      uint32_t* o = t.mutable_data();
      for (uint32_t i = i0; i < i1; ++i) *o++ = m.indices[i] - v0;
      out.append(py::make_tuple(v, t));
    }
    return out;
  }
  py::array_t<double> costs() {
    const std::vector<double>& c = level_view().cell_cost;
    return py::array_t<double>(static_cast<py::ssize_t>(c.size()), c.data());
  }
  void write_gltf(const py::object& target) {
    const std::string out = path_of(target, "write_gltf: path");
    refuse_inputs(out);
    write_level_gltf(out, level_view());
  }
  /// An output may not replace this file's scene or the .pvs itself.
  void refuse_inputs(const std::string& out) const {
    if (same_file(out, path)) throw Error(out, 0, "is the .pvs file read here: write elsewhere");
    refuse_scene(out);
  }
  /// An output may not replace the scene this .pvs was baked from.
  void refuse_scene(const std::string& out) const {
    if (scene_file && same_file(out, scene_file->path))
      throw Error(out, 0, "is the scene this .pvs was baked from: write elsewhere");
  }
  std::vector<std::vector<uint32_t>> neighbours() const { return cells->neighbours(); }
  /// The same view cells and point location with other PVSs, written as a .pvs (checked on
  /// reading back), and read back.
  std::shared_ptr<Baked> with_pvs(const py::object& target, const std::vector<std::vector<uint32_t>>& lists) const {
    const std::string out = path_of(target, "with_pvs: path");
    refuse_scene(out);
    if (lists.size() != file.pvs.cell_count)
      throw Error(out, 0, "with_pvs needs one list per view cell: " + std::to_string(file.pvs.cell_count) +
                              " cells, " + std::to_string(lists.size()) + " lists given");
    PvsFile f = file;
    for (const auto& l : lists)
      for (uint32_t o : l)
        if (o >= f.object_count)
          throw Error(out, 0, "object id " + std::to_string(o) + " is not one of the file's " +
                                  std::to_string(f.object_count) + " objects (0 to " +
                                  std::to_string(f.object_count - 1) + ")");
    std::vector<std::vector<uint32_t>> sorted = lists;
    for (auto& l : sorted) {
      std::sort(l.begin(), l.end());
      l.erase(std::unique(l.begin(), l.end()), l.end());
    }
    f.pvs = recompress_pvs(file.pvs, sorted);
    {
      OutputBatch outputs;
      write_pvs(out, f);
      outputs.commit();
    }
    auto b = std::make_shared<Baked>(out, scene, model);
    b->scene_file = scene_file;
    return b;
  }
};

/// Runs `work` on a thread of its own while this one waits with the GIL released, checking for
/// Ctrl-C every 100 ms: on one, the library's stop is asked for (its loops throw Interrupted,
/// and nothing is written), the thread joined, and KeyboardInterrupt raised here.
void run_interruptible(const std::function<void()>& work) {
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  std::exception_ptr failed;
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      failed = std::current_exception();
    }
    std::lock_guard lock(m);
    done = true;
    cv.notify_all();
  });
  for (;;) {
    {
      py::gil_scoped_release release;
      std::unique_lock lock(m);
      if (cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; })) break;
    }
    if (PyErr_CheckSignals() != 0) {  // KeyboardInterrupt (or what a handler raised) is set
      request_interrupt(true);
      {
        py::gil_scoped_release release;
        worker.join();
      }
      request_interrupt(false);
      throw py::error_already_set();
    }
  }
  {
    py::gil_scoped_release release;
    worker.join();
  }
  if (failed) std::rethrow_exception(failed);
}

/// The play space found from a scene's floors (pipeline::find_play_space), for Python.
struct PlaySpacePy {
  pipeline::FoundPlaySpace found;
  bool has() const { return found.space != nullptr; }
  const FloorSpace& space() const {
    if (!found.space) throw Error("no play space: " + found.why);
    return *found.space;
  }
};

/// A scene argument (a Scene, or a scene file's path) as a source.
pipeline::SceneSource source_of(const py::object& scene, const std::string& what) {
  pipeline::SceneSource source;
  if (py::isinstance<Scene>(scene)) {
    source.scene = scene.cast<std::shared_ptr<Scene>>();
    source.path = source.scene->source;
  } else if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__")) {
    source.path = path_of(scene, what.c_str());
  } else {
    throw py::type_error(what + " must be a viewcells.Scene or a scene file's path, not " +
                         py::str(py::type::of(scene).attr("__name__")).cast<std::string>());
  }
  return source;
}

std::shared_ptr<PlaySpacePy> play_space(const py::object& scene, const std::vector<std::array<double, 3>>& start,
                                        double metres_per_unit, bool only_from_starts, double region_margin,
                                        double player_height, double step, std::array<double, 2> eye_band,
                                        double walk_normal, double floor_cell, double min_region) {
  pipeline::SceneSource source = source_of(scene, "play_space: scene");
  FloorSpaceConfig& f = source.floors;
  f.metres_per_unit = metres_per_unit;
  for (const auto& p : start) f.start_points.push_back({p[0], p[1], p[2]});
  f.only_from_starts = only_from_starts;
  f.region_margin = region_margin;
  f.player_height = player_height;
  f.step = step;
  f.eye_low = eye_band[0];
  f.eye_high = eye_band[1];
  f.walk_normal = walk_normal;
  f.cell = floor_cell;
  f.min_region = min_region;
  auto out = std::make_shared<PlaySpacePy>();
  run_interruptible([&] { out->found = pipeline::find_play_space(source, [](const std::string&) {}); });
  return out;
}

std::shared_ptr<Baked> bake(const py::object& scene, const py::object& output_path, const py::object& progress,
                            const py::kwargs& options) {
  std::shared_ptr<const Scene> memory;
  std::string name;
  if (py::isinstance<Scene>(scene)) {
    memory = scene.cast<std::shared_ptr<Scene>>();
    name = memory->source;
  } else if (py::isinstance<py::str>(scene) || py::hasattr(scene, "__fspath__")) {
    name = path_of(scene, "bake: scene");
  } else {
    throw py::type_error("bake: scene must be a viewcells.Scene or a scene file's path, not " +
                         py::str(py::type::of(scene).attr("__name__")).cast<std::string>());
  }
  const std::string output = path_of(output_path, "bake: output");
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw py::type_error("bake: progress must be callable (it receives each log line), or None");
  pipeline::BakeOptions bake_options;
  bake_options.sampling.scene = name;
  bake_options.bound.output = output;
  std::string report;
  pipeline::BakeConfig config;
  try {
    for (const auto& [k, value] : options) {
      const std::string key = py::str(k);
      if (key == "report") {
        if (!value.is_none()) report = path_of(value, "bake: report");
        continue;
      }
      if (key == "help")
        throw Error("bake: help is not an option of a bake from code; the options are viewcells bake's, as "
                    "keywords:\n" + keyword_listing());
      const pipeline::BakeOption* option = pipeline::find_bake_option(key);
      if (!option || key != option->keyword)
        throw Error("bake: unknown option " + key + " (keyword) (the options are those of `viewcells bake --help`, "
                    "as keywords: max_cells for --max-cells)");
      if (value.is_none()) continue;
      for (const std::string& text : option_texts(*option, key, value))
        pipeline::set_bake_option(bake_options, *option, text, key + " (keyword)");
    }
    config = bake_options.config(progress.is_none());
  } catch (const Error& e) {
    throw Error(as_keywords(e.what()));
  }
  if (memory) config.scene.scene = memory;
  if (!report.empty()) {
    check_output_target(report);
    if (same_file(report, output) || (!memory && same_file(report, name)))
      throw Error(report, 0, "is the .pvs or the scene of this bake: write the report elsewhere");
  }
  pipeline::Log log = [](const std::string&) {};
  if (!progress.is_none())
    log = [&progress](const std::string& line) {
      py::gil_scoped_acquire gil;
      progress(line);
    };
  pipeline::BakeResult result;
  try {
    run_interruptible([&] {
      OutputBatch outputs;  // written in place only when the whole bake succeeded, as the CLI does
      result = pipeline::bake(config, log);
      if (!report.empty()) pipeline::write_report(report, result);
      outputs.commit();
    });
  } catch (const Interrupted&) {
    throw;
  } catch (const Error& e) {
    throw Error(as_keywords(e.what()));  // the library's advice ("raise --max-cells") in Python's words
  }
  auto out = std::make_shared<Baked>(output, *result.file, memory, config.model);
  if (!memory) out->scene_file = config.scene;
  out->report = py::module_::import("json").attr("loads")(pipeline::report_json(result));
  return out;
}

/// A .pvs file written earlier, with the scene it was baked from when given (a Scene, or its
/// file's path and grouping, as `viewcells view --scene` takes them).
std::shared_ptr<Baked> read_baked(const py::object& pvs_path, const py::object& scene, const std::string& objects) {
  const std::string path = path_of(pvs_path, "read: path");
  std::shared_ptr<const Scene> memory;
  if (py::isinstance<Scene>(scene)) memory = scene.cast<std::shared_ptr<Scene>>();
  else if (!scene.is_none() && !py::isinstance<py::str>(scene) && !py::hasattr(scene, "__fspath__"))
    throw py::type_error("read: scene must be a viewcells.Scene, a scene file's path or None, not " +
                         py::str(py::type::of(scene).attr("__name__")).cast<std::string>());
  auto out = std::make_shared<Baked>(path, memory, CostModel{});
  if (!memory && !scene.is_none()) {
    pipeline::SceneSource source;
    source.path = path_of(scene, "read: scene");
    source.grouping = parse_grouping(objects);
    out->scene_file = source;
  }
  return out;
}

}  // namespace

PYBIND11_MODULE(viewcells, m) {
  register_q3_map_format();  // the front end brings the Quake 3 maps (q3/bsp_file.h)
  m.doc() = "viewcells: view cells and potentially visible sets (PVS) for a scene, baked from Python";
  static py::exception<Error> error(m, "Error");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      error(e.what());
    }
  });

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene",
                                            "Triangles grouped into objects: what a PVS lists. From arrays, or "
                                            "Scene.load(path) from a file")
      .def(py::init([](py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
                       const py::object& triangles, const py::object& objects,
                       std::optional<std::vector<std::string>> names, std::optional<std::vector<bool>> see_through,
                       const std::string& name) {
             return std::const_pointer_cast<Scene>(
                 scene_from_arrays(vertices, triangles, objects, names, see_through, name));
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("objects") = py::none(), py::arg("names") = py::none(),
           py::arg("see_through") = py::none(), py::arg("name") = "python scene",
           "vertices (N, 3) float, triangles (M, 3) int, objects (M,) int: each triangle's object (default one "
           "object), names: one per object, see_through: a flag per object. Indices count from 0. Object ids "
           "are kept as given: a PVS lists them, also past an id with no triangles (degenerate triangles are "
           "dropped; an object left with none is never listed). Non-finite coordinates, bad or fractional "
           "indices are errors.")
      .def_static(
          "load",
          [](const std::string& path, const std::string& objects) {
            return std::make_shared<Scene>(load_scene(path, parse_grouping(objects)));
          },
          py::arg("path"), py::arg("objects") = "auto", "A scene file, as the command line reads it")
      .def_property_readonly("object_count", &Scene::object_count)
      .def_property_readonly("triangle_count", &Scene::triangle_count)
      .def_property_readonly("fingerprint", &Scene::fingerprint)
      .def_property_readonly("vertices",
                             [](const Scene& s) {
                               py::array_t<double> a({static_cast<py::ssize_t>(s.vertices.size()), py::ssize_t{3}});
                               auto o = a.mutable_unchecked<2>();
                               for (size_t i = 0; i < s.vertices.size(); ++i)
                                 for (int k = 0; k < 3; ++k) o(i, k) = s.vertices[i][k];
                               return a;
                             }, "(N, 3) float64, as the scene holds them (z up)")
      .def_property_readonly("triangles",
                             [](const Scene& s) {
                               py::array_t<uint32_t> a({static_cast<py::ssize_t>(s.triangles.size()), py::ssize_t{3}});
                               auto o = a.mutable_unchecked<2>();
                               for (size_t i = 0; i < s.triangles.size(); ++i)
                                 for (int k = 0; k < 3; ++k) o(i, k) = s.triangles[i][k];
                               return a;
                             }, "(M, 3) vertex indices")
      .def_property_readonly("triangle_objects",
                             [](const Scene& s) {
                               return py::array_t<uint32_t>(static_cast<py::ssize_t>(s.triangle_object.size()),
                                                            s.triangle_object.data());
                             }, "(M,) each triangle's object")
      .def_property_readonly("object_triangles",
                             [](const Scene& s) {
                               std::vector<uint32_t> n;
                               for (const ObjectInfo& o : s.objects) n.push_back(o.triangle_count);
                               return n;
                             }, "Triangles per object (degenerate ones dropped)")
      .def_property_readonly("names", [](const Scene& s) {
        std::vector<std::string> n;
        for (const ObjectInfo& o : s.objects) n.push_back(o.name);
        return n;
      });

  py::class_<Baked, std::shared_ptr<Baked>>(m, "Baked", "A baked .pvs, read back")
      .def_readonly("path", &Baked::path)
      .def_property_readonly("cell_count", [](const Baked& b) { return b.file.pvs.cell_count; })
      .def_property_readonly("object_count", [](const Baked& b) { return b.file.object_count; })
      .def_property_readonly("object_names", [](const Baked& b) { return b.file.object_names; })
      .def_property_readonly("cell_bounds", &Baked::bounds, "(cells, 2, 3): each cell's box, lo then hi")
      .def("query", &Baked::query, py::arg("point"), "The view cell of a point, or -1 outside the view space")
      .def("pvs", &Baked::pvs, py::arg("cell"), "The cell's visible objects: sorted ids")
      .def_readonly("report", &Baked::report, "What `viewcells bake --report` writes, as a dict (empty when read)")
      .def("polyhedra", &Baked::polyhedra, py::arg("cell"),
           "The cell's convex pieces (its BSP leaves): a list of (vertices (V, 3), faces), each face a list of "
           "vertex indices counter-clockwise seen from outside")
      .def("cut", &Baked::cut, py::arg("count"),
           "The merge history's cut into `count` coarser cells: (the group of each cell, each group's PVS)")
      .def_property_readonly("cell_meshes", &Baked::meshes,
                             "Per cell, its leaves as a mesh (each shrunk 3% towards its centre, as the viewers "
                             "draw them): (vertices (V, 3) float32, triangles (T, 3)). Needs the scene.")
      .def_property_readonly("cell_costs", &Baked::costs,
                             "Per cell, the render cost r(PVS) of its PVS (a + b * triangles per object, the "
                             "viewers' colours). Needs the scene.")
      .def_property_readonly("neighbours", &Baked::neighbours,
                             "Per cell, the cells sharing a part of its boundary of positive area, sorted")
      .def("with_pvs", &Baked::with_pvs, py::arg("path"), py::arg("lists"),
           "Writes the same cells with other PVSs (one list of object ids per cell) to `path` as a .pvs, "
           "compressed through the same hierarchy, and returns it read back")
      .def("write_gltf", &Baked::write_gltf, py::arg("path"),
           "Writes the scene and the cells as binary glTF, as `viewcells view --gltf` does. Needs the scene.");

  m.def("read", &read_baked, py::arg("path"), py::arg("scene") = py::none(), py::arg("objects") = "auto",
        "Reads a .pvs file; `scene` (a Scene or its file's path, with the grouping `objects` it was baked with) "
        "is needed for cell_meshes, cell_costs and write_gltf");

  const FloorSpaceConfig floors;
  py::class_<PlaySpacePy, std::shared_ptr<PlaySpacePy>>(
      m, "PlaySpace", "Where players stand, found from a scene's floors as bake finds its default view space")
      .def_property_readonly("found", &PlaySpacePy::has, "Whether the scene has a play space")
      .def_property_readonly("rule", [](const PlaySpacePy& p) { return p.found.why; },
                             "What was found and how (or why nothing was), in words")
      .def_property_readonly("metres_per_unit", [](const PlaySpacePy& p) { return p.space().metres_per_unit(); })
      .def_property_readonly("volume_m3", [](const PlaySpacePy& p) {
        const double k = p.space().metres_per_unit();
        return p.space().volume() * k * k * k;
      }, "The eye band's volume over the reached floors, m^3")
      .def_property_readonly("floor_area_m2", [](const PlaySpacePy& p) {
        const double k = p.space().metres_per_unit();
        return p.space().floor_area() * k * k;
      }, "The reached floors' area, m^2")
      .def_property_readonly("box", [](const PlaySpacePy& p) {
        const Box3& b = p.space().box();
        return std::array<std::array<double, 3>, 2>{{{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}}};
      }, "((xmin, ymin, zmin), (xmax, ymax, zmax)) of the eye band, scene units")
      .def("contains", [](const PlaySpacePy& p, const std::array<double, 3>& x) {
        return p.space().contains({x[0], x[1], x[2]});
      }, py::arg("point"), "Whether a player's eye can be at the point (scene units)")
      .def("points", [](const PlaySpacePy& p, uint32_t count, uint64_t seed) {
        const std::vector<Vec3> v = p.space().uniform_points(count, seed);
        py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
        auto w = a.mutable_unchecked<2>();
        for (size_t i = 0; i < v.size(); ++i) {
          w(i, 0) = v[i].x;
          w(i, 1) = v[i].y;
          w(i, 2) = v[i].z;
        }
        return a;
      }, py::arg("count"), py::arg("seed") = 1, "(count, 3) points uniform in the play space")
      .def_property_readonly("floors", [](const PlaySpacePy& p) {
        const GroupedMesh g = pipeline::floor_mesh(p.space());
        py::array_t<float> v({static_cast<py::ssize_t>(g.positions.size() / 3), py::ssize_t{3}});
        std::copy(g.positions.begin(), g.positions.end(), v.mutable_data());
        py::array_t<uint32_t> t({static_cast<py::ssize_t>(g.indices.size() / 3), py::ssize_t{3}});
        std::copy(g.indices.begin(), g.indices.end(), t.mutable_data());
        return py::make_tuple(v, t);
      }, "The reached floors to draw, 3 cm above them: (vertices (V, 3) float32, triangles (T, 3))");

  m.def(
      "bake_options",
      [] {
        py::list out;
        const pipeline::BakeOptions defaults;
        for (const pipeline::BakeOption& o : pipeline::bake_option_table()) {
          static const char* kinds[] = {"flag", "whole", "number", "text", "texts"};
          py::dict d;
          d["keyword"] = o.keyword;
          d["flag"] = o.flag;
          d["negation"] = o.negation;
          d["kind"] = kinds[static_cast<int>(o.kind)];
          d["type"] = o.type;
          d["help"] = o.help;
          d["default"] = o.show_default ? py::object(py::str(o.show(defaults))) : py::object(py::none());
          out.append(d);
        }
        return out;
      },
      "The bake's options as the library's table lists them (what `viewcells bake --help` and bake()'s keywords "
      "are made from): a dict each with keyword, flag, negation (a flag's off switch, or ''), kind (flag, whole, "
      "number, text, texts: repeatable), type (the values it takes), help and default (as help shows it, or None).");
  m.def("play_space", &play_space, py::arg("scene"), py::kw_only(), py::arg("start") = std::vector<std::array<double, 3>>{},
        py::arg("metres_per_unit") = floors.metres_per_unit, py::arg("only_from_starts") = floors.only_from_starts,
        py::arg("region_margin") = floors.region_margin, py::arg("player_height") = floors.player_height,
        py::arg("step") = floors.step, py::arg("eye_band") = std::array<double, 2>{floors.eye_low, floors.eye_high},
        py::arg("walk_normal") = floors.walk_normal, py::arg("floor_cell") = floors.cell,
        py::arg("min_region") = floors.min_region,
        "Finds where players stand on `scene` (a Scene or a scene file's path) from its walkable floors, as "
        "bake does for its default view space: the keywords are bake's (start points in scene units, the "
        "rest in metres; metres_per_unit 0: the file's own). A Quake 3 map's play space is its BSP's "
        "leaves: found is False there, and rule says so.");

  static const std::string bake_doc =
      "Bakes `scene` (a Scene, or a scene file's path) into the .pvs file `output`, with `viewcells bake`'s "
      "options as keywords and its defaults (a budget: cells=100 or memory='256K'; report='r.json' writes the "
      "report). progress(line) receives the log lines. Ctrl-C stops the bake within a second with "
      "KeyboardInterrupt, writing nothing (and stops any other bake running in the process: the stop is "
      "process-wide). Returns the file read back.\n\nKeywords (None: the default):\n" + keyword_listing();
  m.def("bake", &bake, py::arg("scene"), py::arg("output"), py::kw_only(), py::arg("progress") = py::none(),
        bake_doc.c_str());
}
