/// `viewcells extract` and `compress`: view cells cut from the merge history, and their PVSs
/// compressed through it (view-cell-construction paper, 5.1-5.2).
#include "viewcells/pipeline/cut.h"

#include <filesystem>
#include <memory>

#include "viewcells/core/format.h"
#include "viewcells/core/error.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/io/scene_io.h"

namespace viewcells::pipeline {

ViewCellSet choose_cells(const SubdivisionFile& file, const CutRule& rule, bool fallback_all) {
  const MergeHistory& h = *file.history;
  const int rules = (rule.count > 0) + rule.memory_given + (rule.cost_ratio != 0);
  if (rules > 1) throw Error("give only one of --count, --memory and --cost-ratio");
  if (rule.count > 0) return extract_by_count(h, rule.count);
  if (rule.memory_given) return extract_by_file_size(file, rule.memory);
  if (rule.cost_ratio != 0) return extract_by_cost_ratio(h, rule.cost_ratio);
  if (!fallback_all) throw Error("say which cells: --count N, --memory BYTES or --cost-ratio R");
  return extract_by_count(h, h.leaf_count);
}

size_t largest_fitting(size_t lo, size_t hi, uint64_t memory, const std::function<uint64_t(size_t)>& bytes_of) {
  size_t best = 0;
  while (lo <= hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (bytes_of(mid) <= memory) {
      best = mid;
      lo = mid + 1;
    } else {
      if (mid == 0) break;
      hi = mid - 1;
    }
  }
  return best;
}

ViewCellSet extract_by_file_size(const SubdivisionFile& file, uint64_t bytes, bool lists_only) {
  const MergeHistory& h = *file.history;
  const std::string rule = std::string(lists_only ? "most cells whose compressed PVS lists fit in "
                                                  : "most cells whose .pvs file fits in ") +
                           std::to_string(bytes) + " bytes";
  auto cut = [&](size_t count) {
    ViewCellSet set = extract_by_count(h, count);
    set.rule = rule;  // the rule is in the file: measure it as written
    return set;
  };
  auto bytes_of = [&](size_t count) {
    const PvsFile pf = pvs_file_for(file, cut(count));
    return lists_only ? compact_pvs_bytes(pf.pvs, pf.object_count) : pvs_file_bytes(pf);
  };
  const size_t n = largest_fitting(h.min_cells(), h.leaf_count, bytes, bytes_of);
  if (n == 0)
    throw Error("a budget of " + std::to_string(bytes) + " bytes is too small: the " +
                (lists_only ? "PVS lists" : ".pvs file") + " of the coarsest " +
                std::to_string(h.min_cells()) + " view cell(s) takes " + std::to_string(bytes_of(h.min_cells())) +
                " bytes");
  return cut(n);
}

SubdivisionFile read_merged(const std::string& path) {
  SubdivisionFile file = read_subdivision(path);
  if (!file.history)
    throw Error(path, 0, "no merge history in this file (it was built with --no-merge, or by an older version)");
  return file;
}

PvsFile pvs_file_for(const SubdivisionFile& file, const ViewCellSet& set) {
  PvsFile pf = make_pvs_file(file.subdivision, file.leaf_pvs, *file.history, set.cells);
  pf.object_count = file.object_count;
  pf.object_names = file.object_names;
  pf.scene_fingerprint = file.scene_fingerprint;
  pf.rule = set.rule;
  return pf;
}

void write_pvs_checked(const std::string& path, const PvsFile& pf, const std::vector<std::vector<uint32_t>>& lists,
                       uint32_t format) {
  write_pvs(path, pf, format);
  const PvsFile back = read_pvs(staged_path(path));  // a command's outputs are renamed at its end
  for (uint32_t i = 0; i < back.pvs.cell_count; ++i)
    if (back.pvs.cell_pvs(i) != lists[i]) throw Error(path, 0, "read-back check failed for cell " + std::to_string(i));
}

RecodeResult recode(const std::string& input, const std::string& output, uint32_t format, const Log& log) {
  RecodeResult out;
  const PvsFile pf = read_pvs(input, &out.version_before);
  std::vector<std::vector<uint32_t>> lists(pf.pvs.cell_count);
  for (uint32_t i = 0; i < pf.pvs.cell_count; ++i) lists[i] = pf.pvs.cell_pvs(i);
  out.file_bytes_before = std::filesystem::file_size(input);
  out.list_bytes_before = list_bytes(pf.pvs.stored, pf.object_count, out.version_before);
  out.list_bytes_after = list_bytes(pf.pvs.stored, pf.object_count, format);
  write_pvs_checked(output, pf, lists, format);
  out.file_bytes_after = std::filesystem::file_size(staged_path(output));
  log("viewcells: " + input + " (format " + std::to_string(out.version_before) + "): lists " +
      std::to_string(out.list_bytes_before) + " bytes, file " + std::to_string(out.file_bytes_before) + " bytes -> " +
      output + " (format " + std::to_string(format) + "): lists " + std::to_string(out.list_bytes_after) + " bytes, file " +
      std::to_string(out.file_bytes_after) + " bytes");
  return out;
}

Scene load_matching_scene(const std::string& path, ObjectGrouping grouping, uint64_t file_fingerprint,
                          const std::string& cells_path) {
  Scene scene = load_scene(path, grouping);
  if (file_fingerprint && scene.fingerprint() != file_fingerprint)
    throw Error(path, 0, "is not the scene " + cells_path + " was built from (fingerprints differ: another scene, "
                         "another version of it, or another --objects grouping)");
  return scene;
}

ExtractResult extract(const ExtractConfig& config, const Log& log) {
  ExtractResult out;
  out.input = config.hierarchy_path;
  out.file = read_merged(config.hierarchy_path);
  const MergeHistory& h = *out.file.history;
  out.set = choose_cells(out.file, config.cut, false);
  log("viewcells: " + std::to_string(out.set.cells.size()) + " view cells (" + out.set.rule + "), render cost " +
      fmt(out.set.cost, 1) + " (elementary cells: " + fmt(h.initial_cost, 1) + "), approximate PVS " +
      std::to_string(out.set.pvs_bytes) + " bytes");
  if (config.views.any()) {
    Subdivision s = out.file.subdivision;
    rebuild_cells(s);
    const CellView view = merged_cell_view(s, h, out.set.cells);
    std::unique_ptr<Scene> scene;
    if (!config.scene_path.empty())
      scene = std::make_unique<Scene>(
          load_matching_scene(config.scene_path, config.grouping, out.file.scene_fingerprint, config.hierarchy_path));
    write_views(s, scene.get(), config.views, log, &view);
  }
  return out;
}

CompressResult compress(const CompressConfig& config, const Log& log) {
  const SubdivisionFile file = read_merged(config.hierarchy_path);
  const ViewCellSet set = choose_cells(file, config.cut, true);
  CompressResult out;
  out.input = config.hierarchy_path;
  out.output = config.output;
  out.flat = config.flat;
  out.rule = set.rule;
  Stopwatch sw;
  const PvsFile pf = pvs_file_for(file, set);
  out.seconds = sw.seconds();
  // Sizes before (every cell lists its whole PVS) and after (each node keeps its part).
  std::vector<std::vector<uint32_t>> flat(pf.pvs.cell_count);
  for (uint32_t i = 0; i < pf.pvs.cell_count; ++i) {
    flat[i] = pf.pvs.cell_pvs(i);
    out.entries_before += flat[i].size();
  }
  out.cells = pf.pvs.cell_count;
  out.objects = pf.object_count;
  out.hierarchy_nodes = pf.pvs.node_count();
  out.entries_after = pf.pvs.stored_entries();
  out.list_bytes_before = list_bytes(flat, pf.object_count);
  out.list_bytes_after = list_bytes(pf.pvs.stored, pf.object_count);
  write_pvs_checked(config.output, pf, flat);
  out.file_bytes = std::filesystem::file_size(staged_path(config.output));
  log("viewcells: " + std::to_string(out.cells) + " view cells (" + set.rule + "): " +
      std::to_string(out.entries_before) + " PVS entries -> " + std::to_string(out.entries_after) + " kept in " +
      std::to_string(out.hierarchy_nodes) + " hierarchy nodes (" +
      fmt(out.entries_before ? double(out.entries_after) / out.entries_before : 1.0, 3) + "); " + config.output +
      ": " + std::to_string(out.file_bytes) + " bytes");
  if (!config.flat.empty()) {
    out.flat_run_length_bytes = write_flat_rows(config.flat, pf);
    out.flat_bit_row_bytes = static_cast<uint64_t>(pf.pvs.cell_count) * ((pf.object_count + 7) / 8);
    out.flat_file_bytes = std::filesystem::file_size(staged_path(config.flat));
    log("viewcells: flat rows -> " + config.flat + ": " + std::to_string(out.flat_bit_row_bytes) +
        " bytes of bit rows, " + std::to_string(out.flat_run_length_bytes) + " run-length coded (Quake style)");
  }
  return out;
}

}  // namespace viewcells::pipeline
