/// `viewcells measure`: a shipped PVS measured by frames a viewer sees (render cost and wrong
/// pixels per camera).
#include "viewcells/pipeline/measure.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <map>
#include <span>

#include "viewcells/cells/view_cells.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/format.h"
#include "viewcells/core/parallel.h"
#include "viewcells/core/progress.h"
#include "viewcells/pvs/pvs.h"

namespace viewcells::pipeline {

CameraPlacement parse_camera_placement(const std::string& name) {
  if (name == "auto") return CameraPlacement::kAuto;
  if (name == "play") return CameraPlacement::kPlay;
  if (name == "view-box") return CameraPlacement::kViewBox;
  throw Error("unknown camera placement '" + name + "' (auto, play, view-box)");
}

namespace {

/// The PVS measured: its rows, and the view cell of a point (-1: none).
struct Measured {
  GlobalPvs pvs;
  std::function<int32_t(const Vec3&)> cell_at;
  std::unique_ptr<CellLocator> locator;  ///< for view-box cameras
};

/// What the engine would draw at each camera: the rendered objects of its cell's PVS (a
/// sampled PVS may also hold the sky or brush hulls, which cost nothing and are not drawn).
void frame_costs(const Scene& scene, const GlobalPvs& pvs, const std::vector<int32_t>& cam_cells,
                 const CostModel& model, MeasureResult& out) {
  CostModel m = model;
  m.c = 0;
  const std::vector<double> cost = per_object_costs(scene, m);
  std::vector<double> cell_cost(pvs.cell_count(), 0.0), cell_tris(pvs.cell_count(), 0.0),
      cell_objects(pvs.cell_count(), 0.0);
  for (uint32_t c = 0; c < pvs.cell_count(); ++c)
    for (uint32_t o : pvs.list(c)) {
      if (!scene.objects[o].rendered) continue;
      cell_cost[c] += cost[o];
      cell_tris[c] += scene.objects[o].triangle_count;
      cell_objects[c] += 1;
    }
  std::vector<double> per_camera;
  for (int32_t c : cam_cells) {
    if (c < 0) {  // in no view cell: the engine has nothing to draw (and every pixel is wrong)
      per_camera.push_back(0);
      continue;
    }
    out.frame_cost += cell_cost[c];
    out.frame_triangles += cell_tris[c];
    out.frame_objects += cell_objects[c];
    per_camera.push_back(cell_cost[c]);
  }
  const double n = static_cast<double>(cam_cells.size());
  out.frame_cost /= n;
  out.frame_triangles /= n;
  out.frame_objects /= n;
  std::sort(per_camera.begin(), per_camera.end());
  const size_t k = per_camera.size();
  out.median_frame_cost = k % 2 ? per_camera[k / 2] : 0.5 * (per_camera[k / 2 - 1] + per_camera[k / 2]);
}

}  // namespace

namespace {

/// The frames with the most wrong pixels (up to 10; ties by camera index), with their cameras.
void worst_frames(const PixelErrorMeasure& e, std::span<const Camera> cameras, std::span<const int32_t> cells,
                  const FrameConfig& frame, std::vector<WrongFrame>& out) {
  std::map<uint32_t, WrongFrame> by_camera;
  for (const WrongView& w : e.wrong) {
    WrongFrame& f = by_camera[w.camera];
    f.camera = w.camera;
    f.pixels += static_cast<double>(w.pixels);
    f.objects.emplace_back(w.object, w.pixels);
  }
  for (auto& [k, f] : by_camera) out.push_back(std::move(f));
  std::sort(out.begin(), out.end(),
            [](const WrongFrame& a, const WrongFrame& b) { return a.pixels != b.pixels ? a.pixels > b.pixels : a.camera < b.camera; });
  if (out.size() > 10) out.resize(10);
  const double scale = static_cast<double>(frame.resolution) / (static_cast<double>(frame.width) * frame.height);
  for (WrongFrame& f : out) {
    f.cell = cells[f.camera];
    f.eye = cameras[f.camera].eye;
    f.forward = cameras[f.camera].forward;
    f.up = cameras[f.camera].up;
    f.pixels *= scale;
    std::sort(f.objects.begin(), f.objects.end(),
              [](const auto& a, const auto& b) { return a.second != b.second ? a.second > b.second : a.first < b.first; });
  }
}

}  // namespace

std::vector<Camera> read_cameras(const std::string& path, double metres_per_unit, std::string* rule) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(read_file_bytes(path));
  } catch (const nlohmann::json::exception& e) {
    throw Error(path, 0, std::string("not a cameras file: ") + e.what());
  }
  const double k = metres_per_unit > 0 ? metres_per_unit : 1.0;
  std::vector<Camera> out;
  try {
    if (j.at("format").get<std::string>() != "viewcells cameras 1") throw Error(path, 0, "not a viewcells cameras file");
    if (rule) *rule = j.value("rule", std::string());
    const auto& list = j.at("cameras");
    if (!list.is_array() || list.empty() || list.size() > 10'000'000)
      throw Error(path, 0, "'cameras' must list 1 to 10,000,000 cameras");
    for (size_t i = 0; i < list.size(); ++i) {
      const std::vector<double> v = list[i].get<std::vector<double>>();
      const auto bad = [&](const std::string& why) {
        return Error(path, 0, "camera " + std::to_string(i) + ": " + why);
      };
      if (v.size() != 9) throw bad("give 9 numbers: eye (metres), forward, up");
      for (double x : v)
        if (!std::isfinite(x)) throw bad("a number is not finite");
      const Vec3 eye{v[0] / k, v[1] / k, v[2] / k}, f{v[3], v[4], v[5]}, u{v[6], v[7], v[8]};
      const Vec3 right = cross(f, u);
      if (!(length(f) > 0.5 && length(u) > 0.5 && length(right) > 0.5))
        throw bad("forward and up must be unit vectors at right angles");
      const Vec3 fn = normalize(f), rn = normalize(right);
      out.push_back({eye, fn, rn, cross(rn, fn)});
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(path, 0, std::string("malformed cameras file: ") + e.what());
  }
  return out;
}

void write_cameras(const std::string& path, const std::vector<Camera>& cameras, double metres_per_unit,
                   const std::string& rule) {
  const double k = metres_per_unit > 0 ? metres_per_unit : 1.0;
  nlohmann::json list = nlohmann::json::array();
  for (const Camera& c : cameras)
    list.push_back({c.eye.x * k, c.eye.y * k, c.eye.z * k, c.forward.x, c.forward.y, c.forward.z, c.up.x, c.up.y, c.up.z});
  write_text_file(path, nlohmann::json{{"format", "viewcells cameras 1"}, {"rule", rule}, {"units", "metres, z up"},
                                       {"cameras", list}}
                            .dump() +
                            "\n");
}

MeasureResult measure(const MeasureConfig& c, const Log& log) {
  Stopwatch total;
  check_frame_budget(c.cameras.count, c.frame.width, c.frame.height);  // before any work
  MeasureResult out;
  out.config = c;
  out.threads = worker_threads();
  if (c.pvs_path.empty() && (c.scene.scene || !is_level_file(c.scene.path)))
    throw Error("measure needs a .pvs file to measure (only a level that brings its own PVS, such as a Quake 3 map, "
                "is measured without one)");

  LoadedScene loaded = load_scene_for_rays(c.scene, log);
  loaded.view_space->check_cameras(c.cameras);  // before the PVS is read
  const Scene& scene = *loaded.scene;
  Measured m;
  std::shared_ptr<const OwnPvs> own;  // the level's own PVS, when measured without a .pvs
  if (!c.pvs_path.empty()) {
    PvsFile f = read_pvs(c.pvs_path);
    if (f.object_count != scene.object_count() || (f.scene_fingerprint && f.scene_fingerprint != scene.fingerprint()))
      throw Error(c.pvs_path, 0, "was not made for the scene " + c.scene.path + " (objects or geometry differ)");
    std::vector<std::vector<uint32_t>> lists(f.pvs.cell_count);
    for (uint32_t i = 0; i < f.pvs.cell_count; ++i) lists[i] = f.pvs.cell_pvs(i);
    m.pvs = GlobalPvs::from_lists(f.object_count, lists);
    out.storage_bytes = std::filesystem::file_size(c.pvs_path);
    out.pvs_bytes = compact_pvs_bytes(f.pvs, f.object_count);
    out.measured = c.pvs_path + " (" + std::to_string(f.pvs.cell_count) + " view cells: " + f.rule + ")";
    m.locator = std::make_unique<CellLocator>(f.bsp, f.leaf_cell, f.pvs.cell_count);
    const CellLocator* loc = m.locator.get();
    m.cell_at = [loc](const Vec3& p) { return loc->cell_at(p); };
  } else {
    if (!loaded.level || !loaded.level->brings_pvs())
      throw Error(c.scene.path, 0, "brings no PVS of its own: give a .pvs file to measure");
    own = loaded.level->own_pvs(scene);
    m.pvs = GlobalPvs::from_lists(static_cast<uint32_t>(scene.object_count()), own->cells);
    out.storage_bytes = out.pvs_bytes = own->bytes;
    out.leaf_surface_bytes = own->extra_bytes;
    out.measured = own->what;
    m.cell_at = own->cell_at;
  }
  out.cells = m.pvs.cell_count();
  out.objects = m.pvs.object_count();
  out.pvs_entries = m.pvs.entries();

  Stopwatch sw;
  CameraSet cams;
  const double mpu = scene.metres_per_unit > 0 ? scene.metres_per_unit : 1.0;
  if (!c.cameras_in.empty()) {
    std::string rule;
    cams.cameras = read_cameras(c.cameras_in, mpu, &rule);
    check_frame_budget(cams.cameras.size(), c.frame.width, c.frame.height);
    for (const Camera& cam : cams.cameras) cams.cells.push_back(m.cell_at(cam.eye));
    cams.rule = "read from " + c.cameras_in + " (" + rule + ")";
  } else {
    cams = loaded.view_space->cameras(scene, *loaded.caster, c.cameras, m.cell_at, m.locator.get());
  }
  if (!c.cameras_out.empty()) write_cameras(c.cameras_out, cams.cameras, mpu, cams.rule);
  const auto uncovered = std::count(cams.cells.begin(), cams.cells.end(), -1);
  if (uncovered)
    log("viewcells: warning: " + std::to_string(uncovered) + " of " + std::to_string(cams.cameras.size()) +
        " player eyes lie in no view cell of " + (c.pvs_path.empty() ? c.scene.path : c.pvs_path) +
        ": an engine gets no PVS there; they are measured as frames drawing nothing");
  const std::vector<Camera>& cameras = cams.cameras;
  const std::vector<int32_t>& cells = cams.cells;
  out.camera_rule = cams.rule;
  out.camera_points_drawn = cams.points_drawn;
  log("viewcells: " + std::to_string(cameras.size()) + " cameras (" + out.camera_rule + ") in " + fmt(sw.seconds(), 2) +
      " s");

  // The frames: first the rate of their rays cast coherently and not, on the same frames.
  out.ray_rates = frame_ray_rates(*loaded.caster, cameras, c.frame);
  log("viewcells: primary rays at " + std::to_string(c.frame.width) + "x" + std::to_string(c.frame.height) + ": " +
      fmt(out.ray_rates.coherent_per_second / 1e6, 1) + " M/s in coherent packets, " +
      fmt(out.ray_rates.incoherent_per_second / 1e6, 1) + " M/s incoherent (" +
      fmt(out.ray_rates.coherent_per_second / out.ray_rates.incoherent_per_second, 2) + "x, the same " +
      std::to_string(out.ray_rates.rays) + " rays)");
  sw.restart();
  GlobalPvs pvs = std::move(m.pvs);
  out.error = measure_frames(scene, *loaded.caster, cameras, cells, pvs, c.frame);
  frame_costs(scene, pvs, cells, c.model, out);

  // Causes and the worst objects.
  std::vector<uint64_t> pixels(scene.object_count(), 0);
  std::vector<uint32_t> seen_by(scene.object_count(), 0);
  std::vector<std::string> cause(scene.object_count(), "missed");
  for (const WrongView& w : out.error.wrong) {
    pixels[w.object] += w.pixels;
    ++seen_by[w.object];
  }
  if (own && own->cause) {
    for (const WrongView& w : out.error.wrong) {
      const std::string why = own->cause(w.object, cameras[w.camera].eye);
      out.wrong_by_cause[why] += w.pixels;
      cause[w.object] = why;
    }
  } else {
    for (const WrongView& w : out.error.wrong) out.wrong_by_cause["missed"] += w.pixels;
  }
  std::vector<uint32_t> order;
  for (uint32_t o = 0; o < scene.object_count(); ++o)
    if (pixels[o]) order.push_back(o);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return pixels[a] != pixels[b] ? pixels[a] > pixels[b] : a < b; });
  if (order.size() > 10) order.resize(10);
  for (uint32_t o : order) out.worst.push_back({o, scene.objects[o].name, pixels[o], seen_by[o], cause[o]});
  worst_frames(out.error, cameras, cells, c.frame, out.worst_frames);

  out.seconds = total.seconds();
  log("viewcells: " + out.measured + ": per frame " + fmt(out.frame_triangles, 4) + " triangles in " +
      fmt(out.frame_objects, 4) + " objects drawn (cost " + fmt(out.frame_cost, 4) + "), wrong pixels " +
      fmt(out.error.pixels, 3) + " per " + std::to_string(c.frame.resolution) + " (median " +
      fmt(out.error.median_pixels, 3) + ", 99th percentile " + fmt(out.error.p99_pixels, 1) + ", worst " +
      fmt(out.error.worst_pixels, 1) + "; " + std::to_string(out.error.cameras_wrong) + " of " +
      std::to_string(out.error.cameras) + " frames wrong" +
      (out.error.cameras_uncovered ? ", " + std::to_string(out.error.cameras_uncovered) + " in no view cell" : "") +
      ") at " + std::to_string(c.frame.width) + "x" + std::to_string(c.frame.height) + ", " + fmt(sw.seconds(), 2) +
      " s");
  return out;
}

}  // namespace viewcells::pipeline
