// vc_bake (include/viewcells/bake.h): the scene from the caller's arrays, the option words
// parsed by the library's table of bake options (pipeline::parse_bake_words: the table
// `viewcells bake` and Python's keywords use too), so that defaults and checks are `viewcells
// bake`'s, and the result returned in memory.
#include "viewcells/bake.h"

#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/options.h"
#include "viewcells/pipeline/report.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/scene/scene.h"

struct vc_bake_result {
  std::string bytes;
  std::string report;
  uint32_t cells = 0;
};

namespace {

using viewcells::Error;

constexpr const char* kName = "(memory)";

void put_error(char* error, size_t size, const std::string& message) {
  if (!error || size == 0) return;
  const size_t n = std::min(size - 1, message.size());
  std::memcpy(error, message.data(), n);
  error[n] = '\0';
}

/// The caller's objects as a scene: one object each, in order.
std::shared_ptr<const viewcells::Scene> scene_from(const vc_bake_object* objects, size_t count) {
  viewcells::RawMesh mesh;
  bool any_see_through = false;
  for (size_t i = 0; i < count; ++i) any_see_through |= objects[i].see_through != 0;
  for (size_t i = 0; i < count; ++i) {
    const vc_bake_object& o = objects[i];
    const std::string name = o.name ? o.name : "object" + std::to_string(i);
    const std::string what = "object " + std::to_string(i) + " (" + name + ")";
    if ((o.vertex_count && !o.vertices) || (o.triangle_count && !o.indices))
      throw Error(kName, 0, what + ": vertices or indices are NULL");
    const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
    if (uint64_t{base} + o.vertex_count > uint64_t{UINT32_MAX})
      throw Error(kName, 0, "more than 2^32 - 1 vertices in all");
    for (uint32_t v = 0; v < o.vertex_count; ++v) {
      mesh.vertices.push_back({o.vertices[3 * v], o.vertices[3 * v + 1], o.vertices[3 * v + 2]});
      if (!viewcells::is_finite(mesh.vertices.back()))
        throw Error(kName, 0, what + ": vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
    }
    for (uint32_t t = 0; t < o.triangle_count; ++t) {
      std::array<uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        const uint32_t index = o.indices[3 * t + k];
        if (index >= o.vertex_count)
          throw Error(kName, 0, what + ": triangle " + std::to_string(t) + " has vertex index " +
                                    std::to_string(index) + ", beyond its " + std::to_string(o.vertex_count) +
                                    " vertices");
        tri[k] = base + index;
      }
      mesh.triangles.push_back(tri);
      mesh.triangle_group.push_back(static_cast<uint32_t>(i));
    }
    mesh.group_names.push_back(name);
    if (any_see_through) mesh.group_occluder.push_back(o.see_through ? 0 : 1);
  }
  mesh.keep_group_ids = true;  // bake.h: an object's id is its position in the array
  return std::make_shared<const viewcells::Scene>(
      viewcells::make_scene(std::move(mesh), viewcells::ObjectGrouping::kGroups, kName));
}

/// Bakes `config` (its scene set here) into a result; the error codes of bake.h.
/// The options vc_bake_config sets, as its fields: the library's messages name flags.
const std::vector<std::pair<std::string, std::string>> kConfigFields = {
    {"--cells", "cells (vc_bake_config)"},
    {"--memory", "memory_bytes (vc_bake_config)"},
    {"--memory-of", "memory_of_lists (vc_bake_config)"},
    {"--samples", "samples (vc_bake_config)"},
    {"--seed", "seed (vc_bake_config)"},
    {"--pixel-error", "pixel_error (vc_bake_config)"},
    {"--agvs-samples", "agvs_samples (vc_bake_config)"},
    {"--holes", "holes (vc_bake_config)"},
    {"--time", "time_seconds (vc_bake_config)"},
    {"--near-samples", "near_samples (vc_bake_config)"},
    {"--play-space", "play_space (vc_bake_config)"},
    {"--prove-hidden", "prove_hidden (vc_bake_config)"},
    {"--conservative", "conservative (vc_bake_config)"},
    {"--metres-per-unit", "metres_per_unit (vc_bake_config)"},
    {"--start", "start_points (vc_bake_config)"}};

/// Bakes `config` from the caller's objects; a message names options as `names` says (empty:
/// as flags, for vc_bake's words).
int run_bake(viewcells::pipeline::BakeConfig config, const vc_bake_object* objects, size_t object_count,
             const char* output, vc_bake_log log, void* user, vc_bake_result** out, char* error, size_t error_size,
             const std::vector<std::pair<std::string, std::string>>& names = {}) {
  try {
    config.scene.scene = scene_from(objects, object_count);
    if (!output) config.output.clear();
    viewcells::pipeline::Log lines = [](const std::string&) {};
    if (log) lines = [log, user](const std::string& line) { log(line.c_str(), user); };
    auto result = std::make_unique<vc_bake_result>();
    {
      viewcells::OutputBatch outputs;  // the file replaced only when the whole bake succeeded
      const viewcells::pipeline::BakeResult baked = viewcells::pipeline::bake(config, lines);
      result->bytes = viewcells::pvs_file_image(*baked.file);
      result->report = viewcells::pipeline::report_json(baked);
      result->cells = baked.cells;
      outputs.commit();
    }
    *out = result.release();
    return 0;
  } catch (const std::bad_alloc&) {
    put_error(error, error_size, "vc_bake: out of memory");
    return 3;
  } catch (const std::exception& e) {
    put_error(error, error_size, names.empty() ? e.what() : viewcells::pipeline::rename_options(e.what(), names));
    return 2;
  }
}

}  // namespace

extern "C" {

vc_bake_config vc_bake_config_default(void) {
  const viewcells::pipeline::BakeConfig d;
  vc_bake_config c{};
  c.cells = d.cells;
  c.memory_bytes = d.memory;
  c.memory_of_lists = d.memory_of_lists;
  c.samples = d.sampling.samples;
  c.seed = d.sampling.seed;
  c.pixel_error = d.agvs.pixel_error;
  c.agvs_samples = d.agvs.max_samples;
  c.holes = d.holes;
  c.time_seconds = d.max_seconds;
  c.near_samples = d.near.rays_per_object;
  c.play_space = d.play_space_where_known;
  c.prove_hidden = d.prove_hidden;
  c.conservative = d.conservative;
  c.metres_per_unit = d.scene.floors.metres_per_unit;
  c.start_points = nullptr;
  c.start_point_count = 0;
  return c;
}

int vc_bake_with_config(const vc_bake_object* objects, size_t object_count, const vc_bake_config* config,
                        const char* output, vc_bake_log log, void* user, vc_bake_result** out, char* error,
                        size_t error_size) {
  if (out) *out = nullptr;
  if (!out || !config || (!objects && object_count) || (config->start_point_count && !config->start_points)) {
    put_error(error, error_size,
              "vc_bake_with_config: out and config must not be NULL, nor objects when object_count is not 0, nor "
              "start_points when start_point_count is not 0");
    return 1;
  }
  viewcells::pipeline::BakeConfig c;
  c.scene.path = kName;
  c.output = output ? output : "";
  c.cells = config->cells;
  c.memory = config->memory_bytes;
  c.memory_of_lists = config->memory_of_lists != 0;
  c.sampling.samples = config->samples;
  c.sampling.seed = c.subdivision.seed = c.agvs.seed = config->seed;
  c.agvs.pixel_error = config->pixel_error;
  c.agvs.max_samples = config->agvs_samples;
  c.holes = config->holes;
  c.max_seconds = config->time_seconds;
  c.near.rays_per_object = config->near_samples;
  c.play_space_where_known = config->play_space != 0;
  c.prove_hidden = config->prove_hidden != 0;
  c.conservative = config->conservative != 0;
  c.scene.floors.metres_per_unit = config->metres_per_unit;
  for (size_t i = 0; i < config->start_point_count; ++i)
    c.scene.floors.start_points.push_back(
        {config->start_points[3 * i], config->start_points[3 * i + 1], config->start_points[3 * i + 2]});
  const bool quiet = log == nullptr;
  c.sampling.show_progress = c.subdivision.show_progress = c.agvs.show_progress = !quiet;
  return run_bake(std::move(c), objects, object_count, output, log, user, out, error, error_size, kConfigFields);
}

int vc_bake(const vc_bake_object* objects, size_t object_count, const char* const* options, const char* output,
            vc_bake_log log, void* user, vc_bake_result** out, char* error, size_t error_size) {
  if (out) *out = nullptr;
  if (!out || (!objects && object_count)) {
    put_error(error, error_size, "vc_bake: out must not be NULL, nor objects when object_count is not 0");
    return 1;
  }
  std::vector<std::string> args = {kName, "-o", output ? output : "(not written).pvs"};
  for (const char* const* w = options; w && *w; ++w) {
    const std::string word = *w;
    if (word == "-o" || word == "--output" || word.rfind("--output=", 0) == 0 || word == "--report" ||
        word.rfind("--report=", 0) == 0) {
      put_error(error, error_size, "vc_bake: " + word + " is not an option here (the output is vc_bake's argument, "
                                   "the report vc_bake_result_report)");
      return 1;
    }
    args.push_back(word);
  }
  viewcells::pipeline::BakeConfig config;
  try {
    config = viewcells::pipeline::parse_bake_words(args).config(log == nullptr);
  } catch (const std::exception& e) {
    put_error(error, error_size, e.what());
    return 2;
  }
  return run_bake(std::move(config), objects, object_count, output, log, user, out, error, error_size);
}

const void* vc_bake_result_bytes(const vc_bake_result* result, size_t* size) {
  if (size) *size = result ? result->bytes.size() : 0;
  return result ? result->bytes.data() : nullptr;
}

const char* vc_bake_result_report(const vc_bake_result* result) { return result ? result->report.c_str() : ""; }

uint32_t vc_bake_result_cells(const vc_bake_result* result) { return result ? result->cells : 0; }

void vc_bake_result_free(vc_bake_result* result) { delete result; }

}  // extern "C"
