#pragma once
/// Scene files: OBJ (keeps `o`/`g` groups), PLY (ASCII and binary), OFF (ASCII) and STL
/// (ASCII and binary), as raw triangles without manifold repair, and an OBJ writer. Every
/// reader is our own and strict: errors name the file and, in text, the line; declared counts
/// are checked against the bytes left before anything is allocated; a truncated file is an
/// error, never a shorter or invented mesh.
#include <istream>
#include <string>
#include <string_view>

#include "viewcells/scene/scene.h"

namespace viewcells {

/// Loads a scene by extension (.obj, .ply, .off, .stl). Throws Error naming the file (and the
/// line for OBJ) when it is missing, malformed, empty or has NaN/infinite coordinates.
Scene load_scene(const std::string& path, ObjectGrouping grouping = ObjectGrouping::kAuto);

/// Largest coordinate magnitude a scene may hold: Embree's rays stop working beyond about 1.8e18.
inline constexpr double kMaxCoordinate = 1e18;

/// Parses OBJ text; `name` is used in error messages. Polygons are fan-triangulated.
RawMesh read_obj(std::istream& in, const std::string& name);
/// Parses the bytes of a PLY, OFF or STL file; `name` is used in error messages.
RawMesh read_ply(std::string_view bytes, const std::string& name);
RawMesh read_off(std::string_view bytes, const std::string& name);
RawMesh read_stl(std::string_view bytes, const std::string& name);

/// Writes the scene as OBJ with one `o` group per object (vertices shared within the file).
/// Writes to a temporary file and renames, so an existing file is never left half-written.
void write_obj(const Scene& scene, const std::string& path);

}  // namespace viewcells
