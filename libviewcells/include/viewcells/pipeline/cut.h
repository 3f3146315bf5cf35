#pragma once
/// Cutting view cells from a merge history: `viewcells extract` (the cells, as JSON and
/// pictures) and `viewcells compress` (their PVSs, compressed through the hierarchy, as .pvs).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/merge/merge.h"
#include "viewcells/pipeline/build.h"
#include "viewcells/pvs/pvs.h"

namespace viewcells::pipeline {

/// Which view cells: at most one rule; none means every elementary cell where allowed.
struct CutRule {
  uint32_t count = 0;        ///< exactly this many
  bool memory_given = false;
  uint64_t memory = 0;       ///< the most cells whose .pvs file (as compress writes it) fits
  double cost_ratio = 0;     ///< the fewest cells within this ratio of the elementary cells' cost
};

/// The view cells `rule` asks for; `fallback_all` takes every elementary cell when no rule is
/// given, else a rule is required (Error).
ViewCellSet choose_cells(const SubdivisionFile& file, const CutRule& rule, bool fallback_all);

/// The most view cells, from lo to hi, whose file of `bytes_of(count)` bytes fits in `memory`
/// (a bisection: the file grows with the cells, each size measured); 0 when none does.
size_t largest_fitting(size_t lo, size_t hi, uint64_t memory, const std::function<uint64_t(size_t)>& bytes_of);
/// The most view cells of the history whose .pvs file, with the hierarchy's own PVSs (what
/// compress writes: point location, hierarchy and compressed lists), is at most `bytes`
/// long, measured. Error naming the smallest file when not even the coarsest cut fits. With
/// `lists_only`, the budget holds for the visible sets alone as a compact runtime handle holds
/// them (compact_pvs_bytes; no point location, names or container), what stands against a map
/// compiler's vis rows.
ViewCellSet extract_by_file_size(const SubdivisionFile& file, uint64_t bytes, bool lists_only = false);

/// Reads a hierarchy file that holds a merge history (Error naming the file otherwise).
SubdivisionFile read_merged(const std::string& path);

/// The .pvs file of the view cells `set` of a built hierarchy, PVSs from its samples.
PvsFile pvs_file_for(const SubdivisionFile& file, const ViewCellSet& set);

/// Writes the .pvs file, then reads it back: every cell's PVS must come back as `lists`.
void write_pvs_checked(const std::string& path, const PvsFile& pf, const std::vector<std::vector<uint32_t>>& lists,
                       uint32_t format = 2);

struct ExtractConfig {
  std::string hierarchy_path;
  CutRule cut;
  std::string scene_path;  ///< drawn into the slice when given; must be the scene the cells were built from
  ObjectGrouping grouping = ObjectGrouping::kAuto;  ///< as the hierarchy was built (the fingerprint counts it)
  ViewsConfig views;
};

/// The scene at `path` when it is the one `file_fingerprint` names (an Error naming both
/// otherwise: cells drawn over another scene's geometry would mislead).
Scene load_matching_scene(const std::string& path, ObjectGrouping grouping, uint64_t file_fingerprint,
                          const std::string& cells_path);

struct ExtractResult {
  std::string input;
  SubdivisionFile file;
  ViewCellSet set;
};

ExtractResult extract(const ExtractConfig& config, const Log& log);

struct CompressConfig {
  std::string hierarchy_path;
  CutRule cut;
  std::string output;  ///< .pvs
  std::string flat;    ///< Quake-style run-length rows (.vflt); empty: none
};

struct CompressResult {
  std::string input, output, flat, rule;
  uint32_t cells = 0, objects = 0;
  uint64_t hierarchy_nodes = 0, entries_before = 0, entries_after = 0;
  uint64_t list_bytes_before = 0, list_bytes_after = 0, file_bytes = 0;
  uint64_t flat_bit_row_bytes = 0, flat_run_length_bytes = 0, flat_file_bytes = 0;
  double seconds = 0;
};

CompressResult compress(const CompressConfig& config, const Log& log);

struct RecodeResult {
  uint32_t version_before = 0;  ///< the input's format version
  uint64_t list_bytes_before = 0, list_bytes_after = 0, file_bytes_before = 0, file_bytes_after = 0;
};

/// Rewrites the .pvs file `input` as `output` in `format` (2, the current one, codes the lists
/// in 1.3-2x fewer bytes than 1), read back and compared cell by cell: the same view cells,
/// point location, names and PVSs.
RecodeResult recode(const std::string& input, const std::string& output, uint32_t format, const Log& log);

}  // namespace viewcells::pipeline
