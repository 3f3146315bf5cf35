// Procedural test scenes in the spirit of the paper's soda (office) and atlanta/vienna (city)
// scenes (view-cell-construction paper, section 6).
#include "viewcells/scene/generators.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "viewcells/core/error.h"
#include "viewcells/core/names.h"
#include "viewcells/core/rng.h"

namespace viewcells {

namespace {
constexpr EnumNames<GeneratorKind, 5> kKindNames{{{{GeneratorKind::kOffice, "office"},
                                                   {GeneratorKind::kCity, "city"},
                                                   {GeneratorKind::kRotatedOffice, "rotated-office"},
                                                   {GeneratorKind::kTown, "town"},
                                                   {GeneratorKind::kGlassCity, "glass-city"}}},
                                                 "scene kind"};
}  // namespace

GeneratorKind parse_generator_kind(const std::string& name) { return kKindNames.parse(name); }

const char* to_string(GeneratorKind kind) { return kKindNames.name(kind); }

namespace {

/// Half the gap left between boxes that a layout places face to face.
constexpr double kHalfGap = 0.001;

class MeshBuilder {
 public:
  explicit MeshBuilder(Scene& scene) : scene_(scene) {}

  /// Starts an object; `occluder` false for a see-through one (glass, water).
  void begin_object(std::string name, bool occluder = true) {
    current_ = static_cast<uint32_t>(scene_.objects.size());
    ObjectInfo info;
    info.name = std::move(name);
    info.occluder = occluder;
    scene_.objects.push_back(std::move(info));
  }

  /// A closed box with outward normals, each face split into a grid (n[a] cells along axis a).
  /// The box is shrunk by kHalfGap on every side so that neighbours never share a face.
  void add_box(Vec3 lo, Vec3 hi, int nx = 1, int ny = 1, int nz = 1) {
    lo += Vec3{kHalfGap, kHalfGap, kHalfGap};
    hi -= Vec3{kHalfGap, kHalfGap, kHalfGap};
    VC_CHECK(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z);
    const int n[3] = {std::max(1, nx), std::max(1, ny), std::max(1, nz)};
    // Vertices on the lattice surface, shared between faces so the box is watertight.
    std::vector<uint32_t> index(static_cast<size_t>(n[0] + 1) * (n[1] + 1) * (n[2] + 1), kNoObject);
    auto vertex = [&](int i, int j, int k) {
      uint32_t& id = index[(static_cast<size_t>(k) * (n[1] + 1) + j) * (n[0] + 1) + i];
      if (id == kNoObject) {
        id = static_cast<uint32_t>(scene_.vertices.size());
        scene_.vertices.push_back({lo.x + (hi.x - lo.x) * i / n[0], lo.y + (hi.y - lo.y) * j / n[1],
                                   lo.z + (hi.z - lo.z) * k / n[2]});
      }
      return id;
    };
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (int side = 0; side < 2; ++side) {
        for (int u = 0; u < n[b]; ++u) {
          for (int v = 0; v < n[c]; ++v) {
            uint32_t q[4];
            const int corners[4][2] = {{u, v}, {u + 1, v}, {u + 1, v + 1}, {u, v + 1}};
            for (int m = 0; m < 4; ++m) {
              int ijk[3];
              ijk[a] = side ? n[a] : 0;
              ijk[b] = corners[m][0];
              ijk[c] = corners[m][1];
              q[m] = vertex(ijk[0], ijk[1], ijk[2]);
            }
            // (b, c) order gives normal +a; reverse it on the low side.
            if (side) {
              add_triangle(q[0], q[1], q[2]);
              add_triangle(q[0], q[2], q[3]);
            } else {
              add_triangle(q[0], q[2], q[1]);
              add_triangle(q[0], q[3], q[2]);
            }
          }
        }
      }
    }
  }

  /// A box of footprint w x d (centred on `centre`, turned `angle` radians about z) from z0
  /// to z1, its faces split about every `step` metres.
  void add_turned_box(Vec3 centre, double w, double d, double z0, double z1, double angle, double step) {
    const size_t first = scene_.vertices.size();
    add_box({-w / 2, -d / 2, z0}, {w / 2, d / 2, z1}, static_cast<int>(w / step) + 1, static_cast<int>(d / step) + 1,
            std::max(1, static_cast<int>((z1 - z0) / step)));
    const double c = std::cos(angle), s = std::sin(angle);
    for (size_t v = first; v < scene_.vertices.size(); ++v) {
      Vec3& p = scene_.vertices[v];
      p = {centre.x + c * p.x - s * p.y, centre.y + s * p.x + c * p.y, p.z};
    }
  }

 private:
  void add_triangle(uint32_t a, uint32_t b, uint32_t c) {
    scene_.triangles.push_back({a, b, c});
    scene_.triangle_object.push_back(current_);
  }
  Scene& scene_;
  uint32_t current_ = kNoObject;
};

// ---------------------------------------------------------------------------------- office

struct OfficeLayout {
  static constexpr double kStorey = 3.2, kSlab = 0.3, kWall = 0.2, kOuter = 0.3;
  static constexpr double kRoomDepth = 5.0, kCorridor = 2.5, kHall = 4.0;
  static constexpr double kDoorWidth = 1.0, kDoorHeight = 2.1;
};

/// Furniture of one room, in bands measured inwards from the facade wall so pieces never
/// overlap: shelf (0.05-0.40 m), desk and chair (0.55-1.85 m), meeting table (1.95-2.95 m).
/// `y_facade` is the room's facade-side edge and `inward` is +1 or -1 along y.
void add_furniture(MeshBuilder& mb, Rng& rng, const std::string& prefix, double x0, double x1,
                   double y_facade, double inward, double z) {
  auto box = [&](double bx0, double u0, double z0, double bx1, double u1, double z1, int nz = 1) {
    const double ya = y_facade + inward * u0, yb = y_facade + inward * u1;
    mb.add_box({bx0, std::min(ya, yb), z + z0}, {bx1, std::max(ya, yb), z + z1}, 1, 1, nz);
  };
  if (rng.uniform() < 0.6) {
    const double w = 0.9, h = rng.uniform(1.2, 2.2);
    const double x = rng.uniform(x0 + 0.1, x1 - w - 0.1);
    mb.begin_object(prefix + "_shelf");
    box(x, 0.05, 0, x + w, 0.40, h, static_cast<int>(h / 0.4));
  }
  if (rng.uniform() < 0.85) {
    const double w = 1.4, u = 0.55, d = 0.7, h = 0.75;
    const double x = rng.uniform(x0 + 0.3, x1 - w - 0.3);
    mb.begin_object(prefix + "_desk");
    box(x, u, h - 0.04, x + w, u + d, h);
    for (double lx : {x, x + w - 0.06})
      for (double lu : {u, u + d - 0.06}) box(lx, lu, 0, lx + 0.06, lu + 0.06, h - 0.04);
    if (rng.uniform() < 0.8) {  // chair on the inner side of the desk
      const double cx = x + w * 0.5 - 0.22, cu = u + d + 0.1;
      mb.begin_object(prefix + "_chair");
      box(cx, cu, 0.42, cx + 0.44, cu + 0.44, 0.47);
      box(cx, cu + 0.40, 0.47, cx + 0.44, cu + 0.44, 0.95);
      for (double lx : {cx, cx + 0.4})
        for (double lu : {cu, cu + 0.4}) box(lx, lu, 0, lx + 0.04, lu + 0.04, 0.42);
    }
  }
  if (x1 - x0 > 4.5 && rng.uniform() < 0.5) {
    const double cx = 0.5 * (x0 + x1);
    mb.begin_object(prefix + "_table");
    box(cx - 0.8, 1.95, 0.70, cx + 0.8, 2.95, 0.74);
    box(cx - 0.1, 2.35, 0, cx + 0.1, 2.55, 0.70);
  }
}

Scene generate_office(uint64_t seed, int size) {
  using L = OfficeLayout;
  Scene scene;
  MeshBuilder mb(scene);
  Rng rng(seed, 0x0ff1ce);
  const int rooms_per_side = 1 + size;
  const int floors = 1 + (size - 1) / 3;

  // Room boundaries along x, shared by all floors (walls stack), random widths 3.5 to 5.5 m.
  std::vector<double> xs{L::kHall};
  for (int r = 0; r < rooms_per_side; ++r) xs.push_back(xs.back() + rng.uniform(3.5, 5.5));
  const double length = xs.back();
  const double width = 2 * L::kRoomDepth + L::kCorridor;
  const double top = floors * L::kStorey + L::kSlab;
  const double ya = L::kRoomDepth, yb = L::kRoomDepth + L::kCorridor;  // corridor edges
  // Stairwell hole in the hall, stairs running along +y.
  const double hx0 = 0.5, hx1 = 3.5, hy0 = 1.0, hy1 = 7.0;

  // Facade: four outer walls spanning the whole height; and the roof.
  const double o = L::kOuter;
  mb.begin_object("facade_south");
  mb.add_box({-o, -o, 0}, {length + o, 0, top}, 1, 1, floors);
  mb.begin_object("facade_north");
  mb.add_box({-o, width, 0}, {length + o, width + o, top}, 1, 1, floors);
  mb.begin_object("facade_west");
  mb.add_box({-o, 0, 0}, {0, width, top}, 1, 1, floors);
  mb.begin_object("facade_east");
  mb.add_box({length, 0, 0}, {length + o, width, top}, 1, 1, floors);

  for (int f = 0; f <= floors; ++f) {
    const double z0 = f * L::kStorey;           // slab bottom
    const double z = z0 + L::kSlab;             // floor level of storey f
    const std::string fp = "f" + std::to_string(f);
    // Slab (the last one is the roof); slabs above ground have the stairwell hole.
    mb.begin_object(f == floors ? "roof" : fp + "_slab");
    if (f == 0 || f == floors) {
      mb.add_box({0, 0, z0}, {length, width, z});
    } else {
      mb.add_box({0, 0, z0}, {hx0, width, z});
      mb.add_box({hx1, 0, z0}, {length, width, z});
      mb.add_box({hx0, 0, z0}, {hx1, hy0, z});
      mb.add_box({hx0, hy1, z0}, {hx1, width, z});
    }
    if (f == floors) break;
    const double ceiling = (f + 1) * L::kStorey;

    // Stairs up to the next floor.
    if (f + 1 < floors) {
      mb.begin_object(fp + "_stairs");
      const int steps = 17;
      const double rise = (ceiling + L::kSlab - z) / steps, run = (hy1 - hy0) / steps;
      for (int s = 0; s < steps; ++s)
        mb.add_box({hx0, hy0 + s * run, z}, {hx1, hy0 + (s + 1) * run, z + (s + 1) * rise});
    }

    for (int side = 0; side < 2; ++side) {
      const char tag = side ? 'b' : 'a';
      // Corridor-side wall centre line and the room strip.
      const double wy = side ? yb : ya;
      const double ry0 = side ? yb + L::kWall / 2 : 0, ry1 = side ? width : ya - L::kWall / 2;
      for (int r = 0; r < rooms_per_side; ++r) {
        const double x0 = xs[r], x1 = xs[r + 1];
        const std::string room = fp + "_room_" + tag + std::to_string(r);
        // Corridor wall with a door opening and a lintel.
        const double door = rng.uniform(x0 + 0.4, x1 - 0.4 - L::kDoorWidth);
        mb.begin_object(room + "_doorwall");
        mb.add_box({x0, wy - L::kWall / 2, z}, {door, wy + L::kWall / 2, ceiling}, 2, 1, 2);
        mb.add_box({door + L::kDoorWidth, wy - L::kWall / 2, z}, {x1, wy + L::kWall / 2, ceiling}, 2, 1, 2);
        mb.add_box({door, wy - L::kWall / 2, z + L::kDoorHeight}, {door + L::kDoorWidth, wy + L::kWall / 2, ceiling});
        // Partition wall at the room's far end (the last one is the facade).
        if (r + 1 < rooms_per_side) {
          mb.begin_object(room + "_partition");
          mb.add_box({x1 - L::kWall / 2, ry0, z}, {x1 + L::kWall / 2, ry1, ceiling}, 1, 2, 2);
        }
        add_furniture(mb, rng, room, x0 + L::kWall / 2, x1 - L::kWall / 2, side ? ry1 : ry0, side ? -1.0 : 1.0, z);
      }
    }
    // The hall between stairwell and rooms is closed off from the rooms by a wall at x = kHall,
    // open to the corridor.
    mb.begin_object(fp + "_hall_wall_a");
    mb.add_box({L::kHall - L::kWall / 2, 0, z}, {L::kHall + L::kWall / 2, ya - L::kWall / 2, ceiling});
    mb.begin_object(fp + "_hall_wall_b");
    mb.add_box({L::kHall - L::kWall / 2, yb + L::kWall / 2, z}, {L::kHall + L::kWall / 2, width, ceiling});
  }
  scene.source = std::string("generated office (size ") + std::to_string(size) + ", seed " + std::to_string(seed) + ")";
  return scene;
}

// ------------------------------------------------------------------------------------ city

Scene generate_city(uint64_t seed, int size, bool glass) {
  Scene scene;
  MeshBuilder mb(scene);
  Rng rng(seed, 0xc17);
  Rng glass_rng(seed, 0x91a55);
  constexpr double kBlock = 60.0, kStreet = 16.0, kPitch = kBlock + kStreet;
  const int blocks = size;
  const double extent = blocks * kPitch + kStreet;

  for (int bi = 0; bi < blocks; ++bi) {
    for (int bj = 0; bj < blocks; ++bj) {
      const std::string bp = "block_" + std::to_string(bi) + "_" + std::to_string(bj);
      const double bx = kStreet + bi * kPitch, by = kStreet + bj * kPitch;
      // Ground tile of this block and the streets south and west of it.
      mb.begin_object(bp + "_ground");
      mb.add_box({bx - kStreet, by - kStreet, -1.0}, {bx + kBlock, by + kBlock, 0.0}, 4, 4, 1);

      // Lots: 2 or 3 per side, each with one building of strongly varying height.
      const int lots_x = 2 + static_cast<int>(rng.below(2)), lots_y = 2 + static_cast<int>(rng.below(2));
      int building = 0;
      for (int lx = 0; lx < lots_x; ++lx) {
        for (int ly = 0; ly < lots_y; ++ly) {
          const double lw = kBlock / lots_x, ld = kBlock / lots_y;
          const double margin = rng.uniform(1.0, 4.0);
          const double x0 = bx + lx * lw + margin, x1 = bx + (lx + 1) * lw - margin;
          const double y0 = by + ly * ld + margin, y1 = by + (ly + 1) * ld - margin;
          // Log-normal heights (median 14 m) with occasional towers.
          double h = std::exp(std::log(14.0) + 0.6 * (rng.uniform() + rng.uniform() + rng.uniform() - 1.5) * 2.0);
          if (rng.uniform() < 0.06) h *= rng.uniform(3.0, 6.0);
          h = std::clamp(h, 5.0, 180.0);
          const int floors = std::max(1, static_cast<int>(h / 3.5));
          mb.begin_object(bp + "_building_" + std::to_string(building++));
          mb.add_box({x0, y0, 0}, {x1, y1, h}, static_cast<int>((x1 - x0) / 5) + 1,
                     static_cast<int>((y1 - y0) / 5) + 1, floors);
          double top = h;
          if (rng.uniform() < 0.3) {  // setback on the roof
            const double s = 0.25;
            const double sx0 = x0 + s * (x1 - x0), sx1 = x1 - s * (x1 - x0);
            const double sy0 = y0 + s * (y1 - y0), sy1 = y1 - s * (y1 - y0);
            const double sh = h * rng.uniform(0.2, 0.6);
            mb.add_box({sx0, sy0, h}, {sx1, sy1, h + sh}, 2, 2, std::max(1, static_cast<int>(sh / 3.5)));
            top = h + sh;
          }
          // Glass city: a curtain wall 0.8 m outside the building, up to above its top (its own
          // random stream, so the city's other draws stay those of the plain city).
          if (glass && glass_rng.uniform() < 0.4) {
            mb.begin_object(bp + "_building_" + std::to_string(building - 1) + "_glass", false);
            mb.add_box({x0 - 0.8, y0 - 0.8, 0}, {x1 + 0.8, y1 + 0.8, top + 1.0}, 2, 2, std::max(1, floors / 4));
          }
        }
      }
      // Glass city: a pool of water along the middle of the street south of the block.
      if (glass && glass_rng.uniform() < 1.0 / 3) {
        mb.begin_object(bp + "_water", false);
        mb.add_box({bx + 2.0, by - kStreet + 5.0, 0.0}, {bx + kBlock - 2.0, by - 5.0, 0.4}, 6, 2, 1);
      }
      // Street furniture along the block's south and west edges: lamps, trees, benches.
      int item = 0;
      for (int edge = 0; edge < 2; ++edge) {
        for (int k = 0; k < 4; ++k) {
          const double t = (k + 0.5) / 4 * kBlock + rng.uniform(-3.0, 3.0);
          const double px = edge ? bx - 2.0 : bx + t, py = edge ? by + t : by - 2.0;
          const std::string name = bp + "_street_" + std::to_string(item++);
          const double kind = rng.uniform();
          if (kind < 0.4) {
            mb.begin_object(name + "_lamp");
            mb.add_box({px - 0.1, py - 0.1, 0}, {px + 0.1, py + 0.1, 6.0}, 1, 1, 3);
            mb.add_box({px - 0.4, py - 0.2, 6.0}, {px + 0.4, py + 0.2, 6.3});
          } else if (kind < 0.8) {
            mb.begin_object(name + "_tree");
            mb.add_box({px - 0.2, py - 0.2, 0}, {px + 0.2, py + 0.2, 3.0}, 1, 1, 2);
            const double r = rng.uniform(1.2, 2.2);
            mb.add_box({px - r, py - r, 3.0}, {px + r, py + r, 3.0 + 2 * r}, 2, 2, 2);
          } else {
            mb.begin_object(name + "_bench");
            mb.add_box({px - 0.9, py - 0.3, 0.4}, {px + 0.9, py + 0.3, 0.5});
            mb.add_box({px - 0.9, py - 0.3, 0}, {px - 0.8, py + 0.3, 0.4});
            mb.add_box({px + 0.8, py - 0.3, 0}, {px + 0.9, py + 0.3, 0.4});
          }
        }
      }
    }
  }
  // Streets on the far (north and east) border.
  mb.begin_object("ground_border_east");
  mb.add_box({extent - kStreet, 0 - 0.0, -1.0}, {extent, extent - kStreet, 0.0}, 1, blocks, 1);
  mb.begin_object("ground_border_north");
  mb.add_box({0, extent - kStreet, -1.0}, {extent, extent, 0.0}, blocks, 1, 1);
  scene.source = std::string(glass ? "generated glass-city (size " : "generated city (size ") + std::to_string(size) +
                 ", seed " + std::to_string(seed) + ")";
  return scene;
}


// ------------------------------------------------------------------------------------ town

/// A district of the town: its own street grid, turned and scaled.
struct District {
  double x, y;        ///< seed point (the districts are its Voronoi cells)
  double angle;       ///< of its streets, radians
  double block, street;
  double height;      ///< median building height
};

/// Whether point (x, y) lies in district k's Voronoi cell at least `gap` (a distance
/// difference) away from every other district.
bool inside_district(const std::vector<District>& ds, size_t k, double x, double y, double gap) {
  const double dk = std::hypot(x - ds[k].x, y - ds[k].y);
  for (size_t j = 0; j < ds.size(); ++j)
    if (j != k && std::hypot(x - ds[j].x, y - ds[j].y) - dk < gap) return false;
  return true;
}

struct Square {
  double x, y, r;
};

/// Buildings of one block (a w x w square centred on `c`, turned with its district): 1 to 3
/// lots per side, one building each, an occasional landmark tower.
void add_town_block(MeshBuilder& mb, Rng& rng, const District& d, Vec3 c, const std::string& name) {
  const double ca = std::cos(d.angle), sa = std::sin(d.angle);
  const int lots_u = 2 + static_cast<int>(rng.below(3)), lots_v = 2 + static_cast<int>(rng.below(3));
  const double lu = d.block / lots_u, lv = d.block / lots_v;
  int building = 0;
  for (int i = 0; i < lots_u; ++i)
    for (int j = 0; j < lots_v; ++j) {
      const double margin = rng.uniform(1.0, 3.5);
      const double w = lu - 2 * margin, dd = lv - 2 * margin;
      if (w < 3 || dd < 3) continue;
      const double u = -d.block / 2 + (i + 0.5) * lu, v = -d.block / 2 + (j + 0.5) * lv;
      double h = std::exp(std::log(d.height) + 0.5 * (rng.uniform() + rng.uniform() + rng.uniform() - 1.5) * 2.0);
      if (rng.uniform() < 0.012) h = rng.uniform(120.0, 260.0);  // a landmark tower
      h = std::clamp(h, 4.0, 260.0);
      mb.begin_object(name + "_building_" + std::to_string(building++));
      const Vec3 centre{c.x + ca * u - sa * v, c.y + sa * u + ca * v, 0};
      mb.add_turned_box(centre, w, dd, 0, h, d.angle, 2.4);
      if (h > 60 && rng.uniform() < 0.5)  // a spire on tall buildings
        mb.add_turned_box(centre, 0.3 * w, 0.3 * dd, h, h + 0.2 * h, d.angle, 2.4);
    }
}

Scene generate_town(uint64_t seed, int size) {
  Scene scene;
  MeshBuilder mb(scene);
  Rng rng(seed, 0x70a);
  constexpr double kUnit = 76.0;
  const double extent = size * kUnit + 16.0;
  const double mid = extent / 2;
  // Districts: Voronoi cells of random seeds, each with its own street angle, block size
  // and (tallest in the middle) building heights.
  std::vector<District> ds(std::max<size_t>(3, static_cast<size_t>(size) * size / 10));
  for (District& d : ds) {
    d.x = rng.uniform(0.0, extent);
    d.y = rng.uniform(0.0, extent);
    d.angle = rng.uniform(0.0, 1.5707963267948966);
    d.block = rng.uniform(30.0, 90.0);
    d.street = rng.uniform(9.0, 20.0);
    const double r = std::hypot(d.x - mid, d.y - mid) / (0.5 * extent);
    d.height = 8.0 + 22.0 * std::exp(-3.0 * r * r);
  }
  std::vector<Square> squares(std::max<size_t>(1, static_cast<size_t>(size) * size / 60));
  for (Square& q : squares) q = {rng.uniform(0.15, 0.85) * extent, rng.uniform(0.15, 0.85) * extent, rng.uniform(20.0, 45.0)};

  // The ground: tiles of an axis-aligned grid, below everything.
  for (int i = 0; i < size; ++i)
    for (int j = 0; j < size; ++j) {
      mb.begin_object("ground_" + std::to_string(i) + "_" + std::to_string(j));
      const double x0 = i * extent / size, y0 = j * extent / size;
      mb.add_box({x0, y0, -1.0}, {x0 + extent / size, y0 + extent / size, 0.0}, 4, 4, 1);
    }
  for (size_t k = 0; k < ds.size(); ++k) {
    const District& d = ds[k];
    const double pitch = d.block + d.street, ca = std::cos(d.angle), sa = std::sin(d.angle);
    const int reach = static_cast<int>(std::ceil(1.5 * extent / pitch));
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j) {
        const double u = i * pitch, v = j * pitch;
        const Vec3 c{d.x + ca * u - sa * v, d.y + sa * u + ca * v, 0};
        bool keep = true;
        for (int corner = 0; corner < 4 && keep; ++corner) {
          const double du = (corner & 1 ? 0.5 : -0.5) * d.block, dv = (corner & 2 ? 0.5 : -0.5) * d.block;
          const double x = c.x + ca * du - sa * dv, y = c.y + sa * du + ca * dv;
          keep = x > 8 && y > 8 && x < extent - 8 && y < extent - 8 && inside_district(ds, k, x, y, d.street);
        }
        for (const Square& q : squares)
          keep = keep && std::hypot(c.x - q.x, c.y - q.y) > q.r + 0.75 * d.block;
        if (keep)
          add_town_block(mb, rng, d, c, "district_" + std::to_string(k) + "_block_" + std::to_string(i) + "_" +
                                            std::to_string(j));
      }
  }
  // Open squares: a ring of trees.
  for (size_t s = 0; s < squares.size(); ++s) {
    const Square& q = squares[s];
    const double ring = q.r - 8.0;
    const int trees = std::max(0, static_cast<int>(2 * 3.14159 * ring / 9.0));
    for (int t = 0; t < trees; ++t) {
      const double a = 2 * 3.141592653589793 * t / trees;
      const double px = q.x + ring * std::cos(a), py = q.y + ring * std::sin(a);
      mb.begin_object("square_" + std::to_string(s) + "_tree_" + std::to_string(t));
      mb.add_box({px - 0.2, py - 0.2, 0}, {px + 0.2, py + 0.2, 3.0}, 1, 1, 2);
      const double r = rng.uniform(1.5, 2.5);
      mb.add_box({px - r, py - r, 3.0}, {px + r, py + r, 3.0 + 2 * r}, 2, 2, 2);
    }
  }
  scene.source = "generated town (size " + std::to_string(size) + ", seed " + std::to_string(seed) + ")";
  return scene;
}

}  // namespace

Scene generate_scene(const GeneratorConfig& config) {
  if (config.size < 1) throw Error("scene size must be at least 1 (got " + std::to_string(config.size) + ")");
  if (config.size > 400) throw Error("scene size " + std::to_string(config.size) + " is too large (at most 400)");
  Scene scene;
  switch (config.kind) {
    case GeneratorKind::kOffice:
    case GeneratorKind::kRotatedOffice: scene = generate_office(config.seed, config.size); break;
    case GeneratorKind::kCity: scene = generate_city(config.seed, config.size, false); break;
    case GeneratorKind::kGlassCity: scene = generate_city(config.seed, config.size, true); break;
    case GeneratorKind::kTown: scene = generate_town(config.seed, config.size); break;
  }
  scene.grouping = ObjectGrouping::kGroups;
  scene.finalize();
  if (config.kind == GeneratorKind::kRotatedOffice) {
    rotate_about_z(scene, 30.0, scene.bounds.center());
    scene.source = "generated rotated-office (size " + std::to_string(config.size) + ", seed " +
                   std::to_string(config.seed) + ", 30 degrees about z)";
  }
  return scene;
}

}  // namespace viewcells
