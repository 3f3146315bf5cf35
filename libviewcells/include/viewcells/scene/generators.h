#pragma once
/// Deterministic scene generators (same kind, seed and size give the same scene, bit for bit),
/// so that tests and demos need no downloads. Z is up; units are metres. Every object is a set
/// of closed, outward-oriented boxes that never touch (1 mm gaps), so generated scenes are
/// solid and empty view space detection applies.
#include <cstdint>
#include <string>

#include "viewcells/scene/scene.h"

namespace viewcells {

enum class GeneratorKind {
  kOffice,         ///< multi-storey interior: rooms along corridors, doors, stairwell, furniture
  kCity,           ///< street grid, buildings of strongly varying heights, street furniture
  kRotatedOffice,  ///< the office rotated 30 degrees about the vertical axis
  /// A city that is not a grid: districts (Voronoi cells) with streets at their own angles and
  /// blocks of their own sizes, taller in the middle, open squares with trees, landmark towers
  kTown,
  /// The city with see-through surfaces (ObjectInfo::occluder false): a glass curtain wall
  /// around two buildings in five, and a pool of water in a third of the streets; for the
  /// see-through path of sampling and subdivision (every crossing adds a segment)
  kGlassCity,
};

/// Parses "office", "city", "rotated-office", "town", "glass-city"; throws Error otherwise.
GeneratorKind parse_generator_kind(const std::string& name);
const char* to_string(GeneratorKind kind);

struct GeneratorConfig {
  GeneratorKind kind = GeneratorKind::kOffice;
  uint64_t seed = 1;
  /// Scale, >= 1. Office: 1 + size rooms per corridor side, 1 + (size-1)/3 floors (size 1 is
  /// about a thousand triangles). City: size x size blocks (size 20 is about a million
  /// triangles and ten thousand objects). Town: about size x size city blocks' area (size 23
  /// is over a million triangles).
  int size = 1;
};

/// Generates the scene; objects are named (e.g. "f0_room_a2_desk", "block_3_4_building_1").
Scene generate_scene(const GeneratorConfig& config);

}  // namespace viewcells
