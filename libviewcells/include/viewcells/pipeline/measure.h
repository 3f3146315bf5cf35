#pragma once
/// `viewcells measure`: what a shipped PVS gives a viewer, measured by frames. The same
/// cameras render the scene; per frame, the render cost of the PVS the engine would draw
/// (that of the camera's view cell) and the pixels it gets wrong (objects shown but missing
/// from that PVS). Any .pvs file of the scene can be measured, and on a Quake 3 map also the
/// map's own PVS (q3map2's cluster rows: visible clusters -> their leaves -> their surfaces),
/// so both sides of a comparison are measured alike. On a map the cameras stand where players
/// do (the scene's view space places them: viewspace/view_space.h); elsewhere at random points of
/// the view box, looking anywhere.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/cells/view_cells.h"
#include "viewcells/eval/frames.h"
#include "viewcells/pipeline/sampling.h"
#include "viewcells/viewspace/view_space.h"

namespace viewcells::pipeline {

// Cameras are the view space's (viewspace/view_space.h): CameraPlacement, CameraConfig, CameraSet.
using viewcells::CameraConfig;
using viewcells::CameraPlacement;
using viewcells::CameraSet;
/// Parses "auto", "play", "view-box" (Error otherwise).
CameraPlacement parse_camera_placement(const std::string& name);

struct MeasureConfig {
  SceneSource scene;
  std::string pvs_path;  ///< the .pvs to measure; empty: the map's own PVS (a Quake 3 map's vis rows)
  CameraConfig cameras;
  FrameConfig frame{1024, 768, 90.0, 1024 * 1024};  ///< what players see (wrong pixels reported per 1024x1024)
  CostModel model;  ///< r(o) of the frame cost (the pixel term is not used)
  /// Cameras from a file written by cameras_out (JSON: eyes, forward and up vectors, in metres),
  /// instead of placing them: the same frames for two versions of a level (a map and its glTF
  /// conversion: the positions are turned into this scene's units, Scene::metres_per_unit, 1
  /// when it does not say). Empty: placed as `cameras` says.
  std::string cameras_in;
  std::string cameras_out;  ///< writes the cameras measured (and their rule) there; empty: not
};

/// Reads cameras written by write_cameras, turned into a scene of `metres_per_unit` (0: 1).
/// Error naming the file on anything malformed.
std::vector<Camera> read_cameras(const std::string& path, double metres_per_unit, std::string* rule = nullptr);
/// Writes cameras of a scene of `metres_per_unit` (0: 1) in metres, with their rule (atomically).
void write_cameras(const std::string& path, const std::vector<Camera>& cameras, double metres_per_unit,
                   const std::string& rule);

/// The objects with the most wrong pixels.
struct WrongObject {
  uint32_t object = 0;
  std::string name;
  uint64_t pixels = 0;
  uint32_t cameras = 0;
  std::string cause;  ///< for the map's own PVS: see MeasureResult::wrong_by_cause; else "missed"
};

/// A frame with wrong pixels, as a camera to look through again (a viewer, a debugger).
struct WrongFrame {
  uint32_t camera = 0;  ///< its index among the cameras (seed and count give the same ones)
  int32_t cell = -1;    ///< its view cell (-1: none)
  Vec3 eye, forward, up;
  double pixels = 0;  ///< wrong pixels, scaled to the resolution
  std::vector<std::pair<uint32_t, uint64_t>> objects;  ///< (object, wrong pixels in this frame), most first
};

struct MeasureResult {
  MeasureConfig config;
  std::string measured;  ///< what was measured, in words
  uint32_t cells = 0, objects = 0;
  uint64_t pvs_entries = 0;
  uint64_t storage_bytes = 0;     ///< the .pvs file, or q3map2's uncompressed cluster rows
  /// The PVSs alone: a .pvs's visible sets as an engine's compact handle holds them
  /// (compact_pvs_bytes: the coded lists and 8 bytes a hierarchy node; without point location
  /// and object names), or q3map2's rows.
  uint64_t pvs_bytes = 0;
  uint64_t leaf_surface_bytes = 0;  ///< q3map2 only: the leaf -> surface lists its renderer also needs
  std::string camera_rule;
  uint64_t camera_points_drawn = 0;
  PixelErrorMeasure error;
  // Per frame (mean over the cameras): what the engine draws, the PVS of the camera's cell.
  double frame_cost = 0;  ///< r(PVS) with the cost model
  double frame_triangles = 0, frame_objects = 0;
  double median_frame_cost = 0;
  /// Wrong pixels by cause. For the map's own PVS:
  ///  - "far": the object lies beyond the map's _farplanedist from the eye (culled on purpose);
  ///  - "unlisted": the object's surface is in no leaf of the map (the game never draws it);
  ///  - "rejected": a line of sight q3map2's PVS rejects (or where the scene models differ).
  /// For a .pvs: "missed" (what sampling did not find).
  std::map<std::string, uint64_t> wrong_by_cause;
  std::vector<WrongObject> worst;  ///< up to 10, most wrong pixels first
  std::vector<WrongFrame> worst_frames;  ///< up to 10 frames, most wrong pixels first
  /// Primary rays a second, coherent packets against incoherent single rays, on the same
  /// frames in this run (frame_ray_rates).
  FrameRayRates ray_rates;
  double seconds = 0;
  int threads = 1;
};

MeasureResult measure(const MeasureConfig& config, const Log& log);

}  // namespace viewcells::pipeline
