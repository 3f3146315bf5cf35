// PVS compression through the merge history, the .pvs file, and Quake-style flat rows.
#include <gtest/gtest.h>

#include "viewcells/runtime.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "viewcells/format/id_lists.h"
#include "support/test_scenes.h"
#include "viewcells/cells/hierarchy_file.h"
#include "viewcells/core/error.h"
#include "viewcells/core/rng.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/merge/merge.h"
#include "viewcells/pvs/pvs.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/scene/generators.h"
#include "viewcells/vis/level_view.h"

namespace viewcells {
namespace {

struct Built {
  Scene scene;
  SegmentSet segs;
  SubdivisionFile file;
};

Built build(GeneratorKind kind, int size, uint64_t samples, uint32_t cells) {
  Built b;
  b.scene = generate_scene({kind, 1, size});
  b.segs = test::sample_scene(b.scene, samples);
  SubdivisionConfig config;
  config.max_cells = cells;
  config.show_progress = false;
  Subdivision s = subdivide(b.scene, b.segs, CostModel{}, config);
  b.file.leaf_pvs = leaf_pvs(s, b.segs);
  MergeConfig mc;
  mc.show_progress = false;
  b.file.history = merge_cells(b.scene, partition_from_subdivision(s, b.file.leaf_pvs), CostModel{}, mc);
  b.file.object_count = static_cast<uint32_t>(b.scene.object_count());
  b.file.scene_fingerprint = b.scene.fingerprint();
  for (const ObjectInfo& o : b.scene.objects) b.file.object_names.push_back(o.name);
  b.file.subdivision = std::move(s);
  return b;
}

/// The PVS of MHT node n from the leaves' PVSs.
std::vector<uint32_t> expected_pvs(const Built& b, int32_t n) {
  const std::vector<int32_t> leaves = b.file.subdivision.leaves();
  std::vector<uint32_t> u;
  for (uint32_t l : b.file.history->leaves_under(n))
    u.insert(u.end(), b.file.leaf_pvs[leaves[l]].begin(), b.file.leaf_pvs[leaves[l]].end());
  std::sort(u.begin(), u.end());
  u.erase(std::unique(u.begin(), u.end()), u.end());
  return u;
}

TEST(Pvs, CompressionIsLosslessAndSmaller) {
  const Built b = build(GeneratorKind::kOffice, 2, 30000, 200);
  const MergeHistory& h = *b.file.history;
  for (size_t count : {200ul, 64ul, 7ul, 1ul}) {
    const std::vector<int32_t> cells = extract_by_count(h, count).cells;
    const PvsFile f = make_pvs_file(b.file.subdivision, b.file.leaf_pvs, h, cells);
    ASSERT_EQ(f.pvs.cell_count, count);
    uint64_t before = 0;
    for (uint32_t i = 0; i < count; ++i) {
      EXPECT_EQ(f.pvs.cell_pvs(i), expected_pvs(b, cells[i])) << "cell " << i;
      before += expected_pvs(b, cells[i]).size();
    }
    // Each node keeps what all cells below it share, so nothing is stored twice on a path.
    for (size_t n = 0; n < f.pvs.node_count(); ++n)
      for (int32_t p = f.pvs.parent[n]; p >= 0; p = f.pvs.parent[p])
        for (uint32_t o : f.pvs.stored[n])
          EXPECT_FALSE(std::binary_search(f.pvs.stored[p].begin(), f.pvs.stored[p].end(), o));
    EXPECT_LE(f.pvs.stored_entries(), before);
    if (count >= 64) {
      EXPECT_LT(f.pvs.stored_entries(), 0.7 * before) << "siblings share most of their PVS";
    }
  }
}

TEST(Pvs, FileRoundTripAndPointLocation) {
  Built b = build(GeneratorKind::kRotatedOffice, 1, 20000, 120);
  const MergeHistory& h = *b.file.history;
  const std::vector<int32_t> cells = extract_by_count(h, 30).cells;
  PvsFile f = make_pvs_file(b.file.subdivision, b.file.leaf_pvs, h, cells);
  f.object_count = b.file.object_count;
  f.object_names = b.file.object_names;
  f.rule = "30 cells";
  const std::string path = test::temp_path("level.pvs");
  write_pvs(path, f);
  const PvsFile back = read_pvs(path);
  EXPECT_EQ(back.object_names, f.object_names);
  EXPECT_EQ(back.rule, "30 cells");
  ASSERT_EQ(back.pvs.cell_count, 30u);
  for (uint32_t i = 0; i < 30; ++i) EXPECT_EQ(back.pvs.cell_pvs(i), f.pvs.cell_pvs(i));
  // A point's cell is the view cell holding its BSP leaf.
  const Subdivision& s = b.file.subdivision;
  Rng rng(9);
  for (int k = 0; k < 300; ++k) {
    const Vec3 p{rng.uniform(s.view_box.lo.x, s.view_box.hi.x), rng.uniform(s.view_box.lo.y, s.view_box.hi.y),
                 rng.uniform(s.view_box.lo.z, s.view_box.hi.z)};
    const int32_t leaf = s.locate(p);
    const int32_t cell = back.locate(p);
    ASSERT_GE(cell, 0);
    const std::vector<uint32_t> under = h.leaves_under(cells[cell]);
    const std::vector<int32_t> leaves = s.leaves();
    const auto it = std::find(leaves.begin(), leaves.end(), leaf);
    ASSERT_NE(it, leaves.end());
    EXPECT_TRUE(std::binary_search(under.begin(), under.end(), static_cast<uint32_t>(it - leaves.begin())));
  }
  EXPECT_EQ(back.locate({1e9, 0, 0}), -1);
  // The copy of the BSP keeps only what separates view cells: fewer leaves than the BSP has,
  // at least one per view cell.
  const auto bsp_leaves = std::count_if(back.leaf_cell.begin(), back.leaf_cell.end(), [](int32_t c) { return c >= 0; });
  EXPECT_LT(bsp_leaves, static_cast<long>(s.leaf_count()));
  EXPECT_GE(bsp_leaves, 30);

  // Truncated, bit-flipped and structurally altered files are rejected with the file's name.
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = test::temp_path("cut.pvs");
  test::write_file(cut, bytes.substr(0, bytes.size() - 10));
  try {
    read_pvs(cut);
    FAIL() << "a truncated file was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cut.pvs"), std::string::npos) << e.what();
  }
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  test::write_file(cut, flipped);
  EXPECT_THROW(read_pvs(cut), Error);
  PvsFile bad = f;
  bad.pvs.parent[0] = 0;  // a cell that is its own parent
  write_pvs(cut, bad);
  EXPECT_THROW(read_pvs(cut), Error);
  bad = f;
  bad.pvs.stored[0].push_back(f.object_count + 5);  // an object that does not exist: not written
  EXPECT_THROW(write_pvs(cut, bad), Error);
  bad = f;
  *std::find_if(bad.leaf_cell.begin(), bad.leaf_cell.end(), [](int32_t c) { return c >= 0; }) = 99;
  write_pvs(cut, bad);
  EXPECT_THROW(read_pvs(cut), Error);
  // A cell whose path keeps an object twice (in the cell and in its parent): the one codec
  // refuses it for the toolkit and for the runtime, both with object counts near the payload's
  // size (each object stamped) and far above it (each path sorted: memory bounded by the file).
  for (const uint32_t objects : {f.object_count, 50'000'000u}) {
    bad = f;
    bad.object_count = objects;
    bad.object_names.clear();
    int32_t cell = 0;
    while (bad.pvs.parent[cell] < 0 || bad.pvs.stored[cell].empty()) ++cell;
    const uint32_t id = bad.pvs.stored[cell][0];
    auto& up = bad.pvs.stored[bad.pvs.parent[cell]];
    up.insert(std::lower_bound(up.begin(), up.end(), id), id);
    write_pvs(cut, bad);
    try {
      read_pvs(cut);
      ADD_FAILURE() << "a path keeping an object twice was accepted (" << objects << " objects)";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("repeats an object"), std::string::npos) << e.what();
    }
    vc_pvs* opened = nullptr;
    char message[256] = "";
    EXPECT_NE(vc_pvs_open(cut.c_str(), &opened, message, sizeof message), 0) << objects;
    EXPECT_NE(std::string(message).find("repeats an object"), std::string::npos) << message;
    EXPECT_NE(vc_pvs_open_compact(cut.c_str(), &opened, message, sizeof message), 0) << objects;
  }
}

TEST(Pvs, QuakeStyleRowsRoundTrip) {
  Rng rng(3);
  for (uint32_t objects : {1u, 7u, 8u, 9u, 300u, 5000u}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<uint32_t> pvs;
      const double density = rng.uniform() * rng.uniform();
      for (uint32_t o = 0; o < objects; ++o)
        if (rng.uniform() < density) pvs.push_back(o);
      const std::string row = rle_row(pvs, objects);
      EXPECT_EQ(unrle_row(row, objects), pvs);
      EXPECT_LE(row.size(), 2 * ((objects + 7) / 8) + 2);
    }
  }
  // Empty rows of many objects shrink to a few bytes: runs of up to 255 zero bytes.
  EXPECT_EQ(rle_row({}, 8 * 600).size(), 6u);
  EXPECT_THROW(unrle_row(std::string("\0", 1), 80), Error);
  EXPECT_THROW(unrle_row(std::string("\x01\x01", 2), 8), Error);
}

std::vector<uint32_t> decoded_one(const std::string& bytes, uint32_t universe, bool* ok) {
  id_lists::BitReader r(bytes.data(), bytes.size());
  std::vector<uint32_t> out;
  *ok = id_lists::get_list(r, universe, out) && r.at_end();
  return out;
}

TEST(Pvs, ListCodingRoundTripsAndIsCompact) {
  // Golden bytes lock the format (format/include/viewcells/format/id_lists.h): the size as Elias gamma of n + 1,
  // then the ids by binary interpolative coding, least significant bit first.
  EXPECT_EQ(id_lists::encode({{2, 3, 7}}, 10), std::string("\x44\x1b", 2));
  EXPECT_EQ(id_lists::encode({{}}, 10), std::string("\x01", 1));
  EXPECT_EQ(id_lists::encode({{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}}, 10), std::string("\x68", 1)) << "a full list is its size";
  EXPECT_EQ(id_lists::encode({}, 10), "");

  Rng rng(5);
  for (uint32_t universe : {1u, 2u, 7u, 100u, 5000u, 1u << 20, 0xffffffffu}) {
    for (int trial = 0; trial < 30; ++trial) {
      std::vector<std::vector<uint32_t>> lists(1 + trial % 4);
      for (auto& l : lists) {
        const double density = std::pow(rng.uniform(), 3.0);
        if (universe <= 5000) {
          for (uint32_t o = 0; o < universe; ++o)
            if (rng.uniform() < density) l.push_back(o);
        } else {  // a few hundred ids, the ends of the range among them
          for (int k = 0; k < 300; ++k) l.push_back(static_cast<uint32_t>(rng.uniform() * universe));
          l.push_back(0);
          l.push_back(universe - 1);
          std::sort(l.begin(), l.end());
          l.erase(std::unique(l.begin(), l.end()), l.end());
        }
      }
      const std::string bytes = id_lists::encode(lists, universe);
      EXPECT_EQ(list_bytes(lists, universe), bytes.size());
      id_lists::BitReader r(bytes.data(), bytes.size());
      for (const auto& l : lists) {
        std::vector<uint32_t> back;
        ASSERT_TRUE(id_lists::get_list(r, universe, back));
        ASSERT_EQ(back, l) << "universe " << universe;
        // Interpolative coding spends at most about log2(universe / n) + 2 bits an id (each
        // truncated binary code is under one bit above log2 of its range); a full list none.
        if (!l.empty() && l.size() < universe) {
          const double n = static_cast<double>(l.size());
          EXPECT_LE(static_cast<double>(id_lists::encode({l}, universe).size()) * 8,
                    n * (std::log2(universe / n) + 2.5) + 2 * std::log2(n + 1) + 9)
              << "universe " << universe << ", " << l.size() << " ids";
        }
      }
      EXPECT_TRUE(r.at_end());
    }
  }
  // A dense list costs under a bit an id, where version 1's varints took a byte.
  std::vector<uint32_t> dense;
  for (uint32_t o = 0; o < 8000; ++o)
    if (o % 10 != 3) dense.push_back(o);
  EXPECT_LT(id_lists::encode({dense}, 8000).size(), dense.size() / 8);

  // Malformed streams are refused, never decoded into something else.
  bool ok = true;
  decoded_one(std::string(5, '\0'), 1000, &ok);  // a gamma code of more than 32 zeros
  EXPECT_FALSE(ok);
  decoded_one(std::string("\x44", 1), 10, &ok);  // the golden list cut short
  EXPECT_FALSE(ok);
  decoded_one(std::string("\x44\x1b\x00", 3), 10, &ok);  // a byte after it
  EXPECT_FALSE(ok);
  decoded_one(std::string("\x44\x3b", 2), 10, &ok);  // a padding bit set
  EXPECT_FALSE(ok);
  EXPECT_EQ(decoded_one(std::string("\x44\x1b", 2), 10, &ok), (std::vector<uint32_t>{2, 3, 7}));
  EXPECT_TRUE(ok);
  decoded_one(id_lists::encode({{0, 1, 2, 3}}, 10), 3, &ok);  // more ids than the universe holds
  EXPECT_FALSE(ok);
  // Whatever the bytes, what decodes is sorted and in range.
  for (int trial = 0; trial < 2000; ++trial) {
    std::string junk(1 + trial % 40, '\0');
    for (char& c : junk) c = static_cast<char>(rng.uniform() * 256);
    const uint32_t universe = 1 + static_cast<uint32_t>(rng.uniform() * 3000);
    id_lists::BitReader r(junk.data(), junk.size());
    std::vector<uint32_t> got;
    while (id_lists::get_list(r, universe, got)) {
      for (size_t i = 0; i < got.size(); ++i) ASSERT_TRUE(got[i] < universe && (i == 0 || got[i - 1] < got[i]));
    }
  }
}

TEST(Pvs, HierarchyFileKeepsTheMergeHistory) {
  const Built b = build(GeneratorKind::kOffice, 1, 15000, 80);
  const std::string path = test::temp_path("merged.vcells");
  write_subdivision(path, b.file);
  const SubdivisionFile back = read_subdivision(path);
  ASSERT_TRUE(back.history.has_value());
  const MergeHistory &h = *b.file.history, &r = *back.history;
  ASSERT_EQ(r.nodes.size(), h.nodes.size());
  EXPECT_EQ(r.cost_after, h.cost_after);
  EXPECT_EQ(r.initial_cost, h.initial_cost);
  for (size_t n = 0; n < h.nodes.size(); ++n) {
    EXPECT_EQ(r.nodes[n].parent, h.nodes[n].parent);
    EXPECT_EQ(r.nodes[n].pvs_size, h.nodes[n].pvs_size);
  }
  EXPECT_EQ(back.object_names, b.file.object_names);
  EXPECT_EQ(extract_by_count(r, 10).cells, extract_by_count(h, 10).cells);
  // An altered history (a merge of nodes that do not exist yet) is rejected.
  SubdivisionFile bad = b.file;
  bad.history->nodes[h.leaf_count].child[0] = static_cast<int32_t>(h.nodes.size() - 1);
  write_subdivision(path, bad);
  EXPECT_THROW(read_subdivision(path), Error);
}

/// The .pvs file of `count` view cells, as compress writes it.
PvsFile pvs_file_of(const Built& b, size_t count) {
  PvsFile f = make_pvs_file(b.file.subdivision, b.file.leaf_pvs, *b.file.history, extract_by_count(*b.file.history, count).cells);
  f.object_count = b.file.object_count;
  f.object_names = b.file.object_names;
  f.scene_fingerprint = b.file.scene_fingerprint;
  return f;
}

/// Signed volume enclosed by the triangles of group g (divergence theorem).
double group_volume(const GroupedMesh& m, size_t g) {
  double v = 0;
  for (uint32_t i = m.first_index[g]; i < m.first_index[g + 1]; i += 3) {
    auto p = [&](uint32_t k) {
      const uint32_t x = m.indices[i + k];
      return Vec3{m.positions[3 * x], m.positions[3 * x + 1], m.positions[3 * x + 2]};
    };
    v += dot(p(0), cross(p(1), p(2))) / 6;
  }
  return v;
}

TEST(LevelView, CellsFillTheViewBoxAndCarryTheirPvs) {
  const Built b = build(GeneratorKind::kOffice, 1, 15000, 80);
  const PvsFile f = pvs_file_of(b, 12);
  const LevelView v = make_level_view(f, b.scene, CostModel{});
  ASSERT_EQ(v.cells.group_count(), 12u);
  ASSERT_EQ(v.scene.group_count(), b.scene.object_count());
  // The cells' leaves, each shrunk by 0.97 about its centroid, fill the view box.
  double volume = 0;
  for (size_t c = 0; c < 12; ++c) {
    const double cv = group_volume(v.cells, c);
    EXPECT_GT(cv, 0) << "cell " << c << " has no outward closed geometry";
    volume += cv;
  }
  const Box3& box = f.bsp.view_box;
  const double box_volume = (box.hi.x - box.lo.x) * (box.hi.y - box.lo.y) * (box.hi.z - box.lo.z);
  EXPECT_NEAR(volume, std::pow(0.97, 3) * box_volume, 1e-4 * box_volume);
  const std::vector<double> base = per_object_costs(b.scene, CostModel{});
  for (uint32_t c = 0; c < 12; ++c) {
    EXPECT_EQ(v.pvs[c], f.pvs.cell_pvs(c));
    double cost = 0;
    for (uint32_t o : v.pvs[c]) cost += base[o];
    EXPECT_DOUBLE_EQ(v.cell_cost[c], cost);
  }
  for (uint32_t o = 0; o < b.scene.object_count(); ++o)
    EXPECT_EQ(v.scene.first_index[o + 1] - v.scene.first_index[o], 3 * b.scene.objects[o].triangle_count);
  // A different scene is refused.
  EXPECT_THROW(make_level_view(f, generate_scene({GeneratorKind::kOffice, 2, 1}), CostModel{}), Error);
  // A view box beyond float's range (a valid file may carry one): glTF and the page store
  // floats, so it is an error, not a .glb whose accessor bounds are null.
  PvsFile far = f;
  far.bsp.view_box.lo.x = -1e308;
  far.bsp.view_box.hi.x = 1e308;
  try {
    make_level_view(far, b.scene, CostModel{});
    FAIL() << "a view box of 1e308 was drawn";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not finite in float"), std::string::npos) << e.what();
  }
}

TEST(LevelView, GltfRoundTripsThroughAssimpWithTheCellsPvsInExtras) {
  const Built b = build(GeneratorKind::kOffice, 1, 15000, 80);
  const PvsFile f = pvs_file_of(b, 9);
  const LevelView v = make_level_view(f, b.scene, CostModel{});
  const std::string path = test::temp_path("level.glb");
  write_level_gltf(path, v);
  // Read back (glTF is y-up; the writer turned z-up into it, the reader turns it back).
  const Scene back = load_scene(path, ObjectGrouping::kNodes);
  ASSERT_EQ(back.object_count(), b.scene.object_count() + 9);
  for (uint32_t o = 0; o < b.scene.object_count(); ++o) {
    const ObjectInfo &a = b.scene.objects[o], &r = back.objects[o];
    EXPECT_EQ(r.name, a.name);
    EXPECT_EQ(r.triangle_count, a.triangle_count);
    EXPECT_NEAR(r.bounds.lo.x, a.bounds.lo.x, 1e-5);
    EXPECT_NEAR(r.bounds.hi.z, a.bounds.hi.z, 1e-5);
    EXPECT_NEAR(r.bounds.lo.y, a.bounds.lo.y, 1e-5);
  }
  for (uint32_t c = 0; c < 9; ++c) EXPECT_FALSE(back.objects[b.scene.object_count() + c].occluder);
  // The cells' extras: id, render cost, PVS.
  std::ifstream in(path, std::ios::binary);
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(glb.substr(0, 4), "glTF");
  uint32_t json_bytes = 0;
  std::memcpy(&json_bytes, glb.data() + 12, 4);
  const auto doc = nlohmann::json::parse(glb.substr(20, json_bytes));
  size_t seen = 0;
  for (const auto& node : doc["nodes"]) {
    if (!node.contains("extras") || !node["extras"].contains("cell")) continue;
    const uint32_t c = node["extras"]["cell"];
    EXPECT_EQ(node["extras"]["pvs"].get<std::vector<uint32_t>>(), f.pvs.cell_pvs(c));
    EXPECT_DOUBLE_EQ(node["extras"]["render_cost"].get<double>(), v.cell_cost[c]);
    ++seen;
  }
  EXPECT_EQ(seen, 9u);
  EXPECT_EQ(doc["asset"]["extras"]["viewcells"]["objects"].size(), b.scene.object_count());
}

}  // namespace
}  // namespace viewcells
