#pragma once
/// What a scene can prove hidden from a region (issue 65): the third answer beside "seen" and
/// "not yet seen". A scene that knows its solid space (a compiled map's BSP, closed convex
/// solids of a mesh) floods its portals from each view cell; an object in no leaf the flood
/// reaches is proven hidden from that cell. The pipeline asks this interface and never which
/// kind of scene it has, as it asks the view space where viewers are.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "viewcells/core/interrupt.h"
#include "viewcells/hidden/portals.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

/// Per view cell, the objects some line from it may reach (sorted): everything else is hidden.
struct HiddenProof {
  std::vector<std::vector<uint32_t>> unhidden;
  uint64_t floods = 0;          ///< convex pieces (cell part in one empty leaf) flooded from
  uint64_t steps = 0;           ///< portals tried
  uint64_t overflows = 0;       ///< floods that ran out of steps and kept all they might see
  uint64_t cells_unproven = 0;  ///< cells not flooded before the deadline: everything unhidden
  double seconds = 0;
};

class HiddenSpace {
 public:
  virtual ~HiddenSpace() = default;
  /// What proves, in words (logs and reports): the kind of solid space, leaves, portals.
  virtual std::string describe() const = 0;
  /// Facts about the solid space a user should know (a leak), in words; empty: none.
  virtual std::vector<std::string> warnings() const { return {}; }
  /// Whether the solid space leaks: empty space where viewers are connects to the outside.
  virtual bool leaks() const { return false; }
  /// Whether p is inside solid space (no viewer stands there; rays from it see back faces).
  virtual bool solid_at(const Vec3& p) const {
    (void)p;
    return false;
  }
  /// Per view cell given as convex pieces (their union holds every viewpoint of the cell), the
  /// objects not proven hidden. Deterministic for any thread count. `max_steps` bounds each
  /// flood; a flood over it keeps everything it might still reach (never less). A cell not
  /// begun when `deadline` passes proves nothing: every object is unhidden (never less).
  virtual HiddenProof prove(const std::vector<std::vector<Polytope>>& cells, uint64_t max_steps,
                            const Deadline& deadline = {}) const = 0;
};

/// Solid space given as a BSP (a compiled map's), with the scene's objects placed in its
/// leaves by their triangles. `what` names it in describe(). When the empty leaves of the
/// points `inside` (where viewers are: a map's spawn points) connect through portals to an
/// empty leaf open to the outer box, the space leaks, and warnings() says where.
std::shared_ptr<const HiddenSpace> bsp_hidden_space(SolidBsp bsp, const Scene& scene, const std::string& what,
                                                    const std::vector<Vec3>& inside);

/// A convex solid: the points behind (distance <= 0) all its planes; `vertices` its corners.
struct Brush {
  std::vector<HalfPlane> planes;
  std::vector<Vec3> vertices;
};
/// A BSP whose solid leaves are exactly the union of the brushes (each at most 64 planes),
/// over `bounds`. Error when it would exceed `max_nodes`.
SolidBsp solid_bsp_from_brushes(const std::vector<Brush>& brushes, const Box3& bounds, size_t max_nodes = 2'000'000);

/// The scene's closed, outward-oriented, convex objects that stop rays, as brushes; the others
/// counted in `skipped` (not closed, not convex, more than 64 planes, see-through).
std::vector<Brush> convex_solid_brushes(const Scene& scene, uint64_t& skipped);

/// Solid space from the scene's convex solids (convex_solid_brushes); null, with the reason in
/// `why`, when the scene has none.
std::shared_ptr<const HiddenSpace> solid_objects_hidden_space(const Scene& scene, std::string& why);

}  // namespace viewcells
