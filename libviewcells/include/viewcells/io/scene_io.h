#pragma once
/// Scene files: OBJ (own reader, keeps `o`/`g` groups and line numbers), PLY, OFF and STL
/// (through OpenMesh, raw triangles without manifold repair), and an OBJ writer.
#include <istream>
#include <string>

#include "viewcells/scene/scene.h"

namespace viewcells {

/// Loads a scene by extension (.obj, .ply, .off, .stl). Throws Error naming the file (and the
/// line for OBJ) when it is missing, malformed, empty or has NaN/infinite coordinates.
Scene load_scene(const std::string& path, ObjectGrouping grouping = ObjectGrouping::kAuto);

/// Parses OBJ text; `name` is used in error messages. Polygons are fan-triangulated.
RawMesh read_obj(std::istream& in, const std::string& name);

/// Writes the scene as OBJ with one `o` group per object (vertices shared within the file).
/// Writes to a temporary file and renames, so an existing file is never left half-written.
void write_obj(const Scene& scene, const std::string& path);

}  // namespace viewcells
