// The Python module `viewcells`: bake view cells and their PVSs from Python, with a scene from
// numpy arrays (an editor's meshes) or from a file, and read the result back as arrays.
//
//   import viewcells, numpy as np
//   scene = viewcells.Scene(vertices, triangles, objects=ids, names=names, see_through=flags)
//   baked = viewcells.bake(scene, "level.pvs", cells=100, pixel_error=5, progress=print)
//   baked.query((3, 12, 1.5)), baked.pvs(cell), baked.cell_bounds, baked.report
//
// bake() takes the command line's options as keywords (cells=100 is --cells 100, no_ga=True
// is --no-ga) and parses them with the command line's own code (cli::bake_config_from_args),
// so its defaults and checks are exactly `viewcells bake`'s; the scene then comes from memory
// (pipeline::SceneSource::scene) when it is a Scene. Errors are viewcells.Error carrying the
// library's message.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "viewcells/cells/view_cells.h"
#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/scene/scene.h"

namespace py = pybind11;
using namespace viewcells;

namespace {

/// A scene from arrays: vertices (N x 3, float64), triangles (M x 3, integer indices), per
/// triangle its object (M; default: one object), object names, and which objects are seen
/// through (glass, water: in PVSs, hiding nothing).
std::shared_ptr<const Scene> scene_from_arrays(py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
                                               py::array_t<int64_t, py::array::c_style | py::array::forcecast> triangles,
                                               std::optional<py::array_t<int64_t, py::array::c_style | py::array::forcecast>> objects,
                                               std::optional<std::vector<std::string>> names,
                                               std::optional<std::vector<bool>> see_through, const std::string& name) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw Error(name, 0, "vertices must be an array of shape (N, 3)");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3) throw Error(name, 0, "triangles must be an array of shape (M, 3)");
  RawMesh mesh;
  const auto v = vertices.unchecked<2>();
  for (py::ssize_t i = 0; i < v.shape(0); ++i) mesh.vertices.push_back({v(i, 0), v(i, 1), v(i, 2)});
  const auto t = triangles.unchecked<2>();
  for (py::ssize_t i = 0; i < t.shape(0); ++i) {
    std::array<uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      if (t(i, k) < 0 || t(i, k) >= v.shape(0))
        throw Error(name, 0, "triangle " + std::to_string(i) + " has a vertex index out of range");
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
      if (o(i) < 0 || o(i) >= (int64_t{1} << 31)) throw Error(name, 0, "object ids must be from 0 to 2^31 - 1");
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
  return std::make_shared<const Scene>(make_scene(std::move(mesh), ObjectGrouping::kGroups, name));
}

/// A keyword argument as command-line words: cells=100 -> --cells 100, no_ga=True -> --no-ga,
/// a list -> the option once with every value.
void add_option(std::vector<std::string>& args, const std::string& key, const py::handle& value) {
  std::string option = "--" + key;
  for (char& c : option)
    if (c == '_') c = '-';
  if (py::isinstance<py::bool_>(value)) {
    if (value.cast<bool>()) args.push_back(option);
    return;
  }
  if (value.is_none()) return;
  args.push_back(option);
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    for (const py::handle& item : value) args.push_back(py::str(item));
    return;
  }
  args.push_back(py::str(value));
}

/// What a bake wrote, read back: the view cells (their point location, bounds and PVSs), the
/// report as a dict.
struct Baked {
  std::string path;
  PvsFile file;
  std::unique_ptr<CellLocator> cells;
  py::dict report;

  int32_t query(const std::array<double, 3>& p) const {
    const Vec3 q{p[0], p[1], p[2]};
    return cells->cell_at(q);
  }
  py::array_t<uint32_t> pvs(int64_t cell) const {
    if (cell < 0 || cell >= file.pvs.cell_count) throw Error(path, 0, "no view cell " + std::to_string(cell));
    const std::vector<uint32_t> ids = file.pvs.cell_pvs(static_cast<uint32_t>(cell));
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
};

std::shared_ptr<Baked> bake(const py::object& scene, const std::string& output, const py::object& progress,
                            const py::kwargs& options) {
  std::shared_ptr<const Scene> memory;
  std::string name;
  if (py::isinstance<py::str>(scene)) {
    name = scene.cast<std::string>();
  } else {
    memory = scene.cast<std::shared_ptr<const Scene>>();
    name = memory->source;
  }
  std::vector<std::string> args = {name, "-o", output};
  for (const auto& [key, value] : options) add_option(args, py::str(key), value);
  pipeline::BakeConfig config = cli::bake_config_from_args(args, progress.is_none());
  if (memory) config.scene.scene = memory;
  pipeline::Log log = [](const std::string&) {};
  if (!progress.is_none())
    log = [&progress](const std::string& line) {
      py::gil_scoped_acquire gil;
      progress(line);
    };
  pipeline::BakeResult result;
  {
    py::gil_scoped_release release;
    OutputBatch outputs;  // written in place only when the whole bake succeeded, as the CLI does
    result = pipeline::bake(config, log);
    outputs.commit();
  }
  auto out = std::make_shared<Baked>();
  out->path = output;
  out->file = read_pvs(output);
  out->cells = std::make_unique<CellLocator>(out->file.bsp, out->file.leaf_cell, out->file.pvs.cell_count);
  out->report = py::module_::import("json").attr("loads")(pipeline::report_json(result));
  return out;
}

}  // namespace

PYBIND11_MODULE(viewcells, m) {
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
                       py::array_t<int64_t, py::array::c_style | py::array::forcecast> triangles,
                       std::optional<py::array_t<int64_t, py::array::c_style | py::array::forcecast>> objects,
                       std::optional<std::vector<std::string>> names, std::optional<std::vector<bool>> see_through,
                       const std::string& name) {
             return std::const_pointer_cast<Scene>(
                 scene_from_arrays(vertices, triangles, objects, names, see_through, name));
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("objects") = py::none(), py::arg("names") = py::none(),
           py::arg("see_through") = py::none(), py::arg("name") = "python scene",
           "vertices (N, 3) float, triangles (M, 3) int, objects (M,) int: each triangle's object (default one "
           "object), names: one per object, see_through: a flag per object. Degenerate triangles are dropped; "
           "non-finite coordinates and bad indices are errors.")
      .def_static(
          "load",
          [](const std::string& path, const std::string& objects) {
            return std::make_shared<Scene>(load_scene(path, parse_grouping(objects)));
          },
          py::arg("path"), py::arg("objects") = "auto", "A scene file, as the command line reads it")
      .def_property_readonly("object_count", &Scene::object_count)
      .def_property_readonly("triangle_count", &Scene::triangle_count)
      .def_property_readonly("fingerprint", &Scene::fingerprint)
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
      .def_readonly("report", &Baked::report, "What `viewcells bake --report` writes, as a dict");

  m.def("bake", &bake, py::arg("scene"), py::arg("output"), py::kw_only(), py::arg("progress") = py::none(),
        "Bakes `scene` (a Scene, or a scene file's path) into the .pvs file `output`, with `viewcells bake`'s "
        "options as keywords and its defaults (cells=100 or memory='256K'; pixel_error, holes='1%', time, ...). "
        "progress(line) receives the log lines. Returns the file read back.");
}
