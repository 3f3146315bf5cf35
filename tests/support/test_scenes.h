#pragma once
// Small scenes built in code for tests, and helpers shared by several test files.
#include <string>

#include "viewcells/agvs/agvs.h"
#include "viewcells/sampling/segments.h"
#include "viewcells/scene/scene.h"

namespace viewcells::test {

/// A closed, outward-oriented unit cube [lo, hi] as a RawMesh group (appended to `mesh`).
void add_cube(RawMesh& mesh, const Vec3& lo, const Vec3& hi, const std::string& group);
/// A scene of `n` x `n` cubes on a grid, each an object; closed and solid.
Scene cube_grid(int n, double spacing = 3.0, double size = 1.0);
/// Visibility segments of `samples` samples (Embree, default settings, no progress bar).
SegmentSet sample_scene(const Scene& scene, uint64_t samples, uint64_t seed = 1);
/// View cells for AGVS tests: the `n` leaves of a KD-CASM tree built from `samples` samples
/// (seed 3), one cell each.
CellLocator kd_cells(const Scene& scene, uint32_t n, uint64_t samples = 20000);
/// A temporary directory unique to this test process; files are removed at exit.
std::string temp_path(const std::string& name);
/// Writes text to a file (for loader tests).
void write_file(const std::string& path, const std::string& text);
/// OpenArena's oa_dm2 from scripts/fetch-maps.sh's cache under `data_dir`, or "" (the test then
/// skips; with VIEWCELLS_REQUIRE_MAPS set, its absence is also a failure).
std::string oa_dm2_path(const std::string& data_dir);

}  // namespace viewcells::test
