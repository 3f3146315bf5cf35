#pragma once
/// Proving what is hidden (issue 65): a BSP of solid and empty space, the portals between its
/// empty leaves, and a conservative flood from a convex region through the portal sequences a
/// line can still stab (the separating planes of a map compiler's vis: Teller's antipenumbra,
/// clipped one portal at a time). A leaf the flood does not reach is seen by no line from the
/// region; an object with no part in a reached leaf is proven hidden, with no ray cast.
/// Arithmetic is double with tolerances that keep more, never less: sources and windings are
/// clipped with slack outwards, a separating plane is used only when it separates with room to
/// spare, and a flood that exceeds its step budget marks everything it might still reach.
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/core/vec3.h"

namespace viewcells {

/// A plane normal . x = dist; the positive side (front) is where the normal points.
struct HalfPlane {
  Vec3 normal;
  double dist = 0;
  double distance(const Vec3& p) const { return dot(normal, p) - dist; }
};

/// A BSP over all of space whose leaves are solid (stop every line) or empty.
struct SolidBsp {
  std::vector<HalfPlane> planes;
  struct Node {
    int32_t plane = 0;
    int32_t children[2] = {0, 0};  ///< [0] front, [1] back; >= 0: node, < 0: leaf -(child + 1)
  };
  std::vector<Node> nodes;          ///< node 0 is the root (no nodes: a single leaf 0)
  std::vector<uint8_t> leaf_solid;  ///< per leaf
  Box3 bounds;                      ///< everything of interest lies inside; portals are clipped to it
  /// How far off a plane of the tree a scene surface lying on that plane may be found: a
  /// compiled map stores its planes as floats, so its faces lie up to ~1e-3 units off them at
  /// 4096 units. An object polygon that close to a plane is placed on both sides (always the
  /// safe way: more leaves hold it). 0: the tree's own tolerance, 1e-7 of its diagonal.
  double surface_slack = 0;
  size_t leaf_count() const { return leaf_solid.size(); }
  /// The leaf holding p.
  int32_t leaf_at(const Vec3& p) const;
};

/// A convex polygon, its vertices in order.
using Winding = std::vector<Vec3>;

/// A convex polytope as its face polygons (any orientation).
struct Polytope {
  std::vector<Winding> faces;
  bool empty() const { return faces.empty(); }
  static Polytope box(const Box3& b);
  /// Vertices of all faces (each once, up to `weld`).
  std::vector<Vec3> vertices(double weld) const;
};

/// The part of `w` where plane.distance(x) >= -slack (empty when none).
Winding clip_winding(const Winding& w, const HalfPlane& plane, double slack);
/// The part of `p` where plane.distance(x) >= -slack, capped (empty when none).
Polytope clip_polytope(const Polytope& p, const HalfPlane& plane, double slack);

/// The portals of a SolidBsp: the polygons where two empty leaves meet, inside bsp.bounds.
class PortalGraph {
 public:
  struct Portal {
    Winding winding;
    HalfPlane plane;       ///< normal into `to`
    int32_t from = 0, to = 0;
  };
  /// Builds the portals (both directions of each) and each portal's might-see set (the portals
  /// a line through it can reach at all, the basic flood of a map compiler's vis).
  explicit PortalGraph(SolidBsp bsp);

  const SolidBsp& bsp() const { return bsp_; }
  size_t portal_count() const { return portals_.size(); }
  const Portal& portal(size_t i) const { return portals_[i]; }
  const std::vector<uint32_t>& leaf_portals(int32_t leaf) const { return out_[static_cast<size_t>(leaf)]; }
  /// Empty leaves whose space reaches the outer box (bsp.bounds): the space is open to the
  /// outside there. On a map that should be sealed (a compiled Quake 3 map), that is a leak.
  const std::vector<int32_t>& open_leaves() const { return open_; }
  /// Distances below this are rounding (map units): a millionth of the bounds' diagonal.
  double tolerance() const { return eps_; }

  /// The convex polygon `w` cut by the BSP: each empty leaf it has area or an edge in, with its
  /// part there (a part on a split plane goes to both sides).
  void split_polygon(const Winding& w, std::vector<std::pair<int32_t, Winding>>& out) const;
  /// The convex polytope `p` cut by the BSP: each empty leaf it reaches, with its part there.
  void split_to_leaves(const Polytope& p, std::vector<std::pair<int32_t, Polytope>>& out) const;

  /// The objects to decide: every convex polygon of object `object` (a triangle, or its part)
  /// that lies in empty leaf `leaf`. Replaces what was placed before.
  struct Placed {
    int32_t leaf = 0;
    uint32_t object = 0;
    Winding polygon;
  };
  void place(std::vector<Placed> placed, uint32_t object_count);

  struct FloodStats {
    uint64_t steps = 0;       ///< portals tried
    uint64_t overflows = 0;   ///< floods that ran out of steps (kept all they might see)
  };
  /// What the floods of one region found: portals crossed, objects reached.
  struct FloodState {
    std::vector<uint64_t> visible, done, overflow;  ///< bits per portal
    std::vector<uint8_t> object_seen;               ///< per object
    std::vector<uint32_t> remaining;                ///< per leaf: its objects not yet seen
  };
  /// Empties `state` for a new region.
  void reset(FloodState& state) const;
  /// Adds to `state` what some line from the convex region `source` (which lies in empty leaf
  /// `start`, up to the tolerance) can reach: the portals it crosses, and each placed polygon
  /// that such a line meets beyond the last portal (the antipenumbra's separating planes, not
  /// only the leaf). `max_steps` bounds the work of this call; over it, everything the
  /// portal sequence might still reach is kept.
  void flood(const Polytope& source, int32_t start, FloodState& state, uint64_t max_steps, FloodStats& stats) const;
  /// Marks the objects of every leaf an overflowing flood kept (after the region's floods).
  void finish(FloodState& state) const;

 private:
  void make_portals();
  void make_might_see();
  SolidBsp bsp_;
  std::vector<Portal> portals_;
  std::vector<std::vector<uint32_t>> out_;  ///< per leaf, portals leaving it
  std::vector<int32_t> open_;
  std::vector<uint64_t> might_;             ///< portal_count rows of words_
  std::vector<std::vector<uint32_t>> in_;   ///< per leaf, portals entering it
  std::vector<std::vector<Placed>> placed_;  ///< per leaf
  std::vector<std::vector<int32_t>> object_leaves_;
  std::vector<uint32_t> leaf_objects_;      ///< per leaf: distinct objects placed there
  size_t words_ = 0;
  double eps_ = 1e-6;
  friend struct FloodRun;
};

}  // namespace viewcells
