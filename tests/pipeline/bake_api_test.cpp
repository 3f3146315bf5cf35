// vc_bake (capi/include/viewcells/bake.h): a scene in memory baked from C gives the file a bake
// of the same scene from an OBJ gives, byte for byte; the runtime opens its bytes from memory;
// see-through objects hide nothing; bad arguments get a message and a non-zero code, and a
// failing bake leaves an earlier file as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "support/test_scenes.h"
#include "viewcells/bake.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/pipeline/bake.h"
#include "viewcells/pipeline/options.h"
#include "viewcells/runtime.h"
#include "viewcells/scene/generators.h"

namespace viewcells {
namespace {

/// A scene as an engine holds it: per object, its own vertices and triangles.
struct Meshes {
  std::vector<std::string> names;
  std::vector<std::vector<double>> vertices;
  std::vector<std::vector<uint32_t>> indices;
  std::vector<int> see_through;
  std::vector<vc_bake_object> objects() const {
    std::vector<vc_bake_object> out;
    for (size_t i = 0; i < names.size(); ++i)
      out.push_back({names[i].c_str(), vertices[i].data(), static_cast<uint32_t>(vertices[i].size() / 3),
                     indices[i].data(), static_cast<uint32_t>(indices[i].size() / 3), see_through[i]});
    return out;
  }
  /// The same as an OBJ file: an `o` line per object, its vertices, its faces.
  std::string obj() const {
    std::string text;
    size_t base = 1;
    char line[128];
    for (size_t i = 0; i < names.size(); ++i) {
      text += "o " + names[i] + "\n";
      for (size_t v = 0; v < vertices[i].size(); v += 3) {
        std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", vertices[i][v], vertices[i][v + 1], vertices[i][v + 2]);
        text += line;
      }
      for (size_t t = 0; t < indices[i].size(); t += 3) {
        std::snprintf(line, sizeof line, "f %zu %zu %zu\n", base + indices[i][t], base + indices[i][t + 1],
                      base + indices[i][t + 2]);
        text += line;
      }
      base += vertices[i].size() / 3;
    }
    return text;
  }
};

/// The generated office split into its objects, each with the vertices its triangles use.
Meshes office() {
  const Scene s = generate_scene({GeneratorKind::kOffice, 1, 1});
  Meshes m;
  for (uint32_t o = 0; o < s.object_count(); ++o) {
    m.names.push_back("object_" + std::to_string(o));
    m.vertices.emplace_back();
    m.indices.emplace_back();
    m.see_through.push_back(0);
    std::vector<int64_t> local(s.vertices.size(), -1);
    for (size_t t = 0; t < s.triangles.size(); ++t) {
      if (s.triangle_object[t] != o) continue;
      for (uint32_t v : s.triangles[t]) {
        if (local[v] < 0) {
          local[v] = static_cast<int64_t>(m.vertices.back().size() / 3);
          m.vertices.back().insert(m.vertices.back().end(), {s.vertices[v].x, s.vertices[v].y, s.vertices[v].z});
        }
        m.indices.back().push_back(static_cast<uint32_t>(local[v]));
      }
    }
  }
  return m;
}

const std::vector<std::string> kOptions = {"--cells", "12", "--samples", "20000", "--agvs-samples", "40000",
                                           "--seed", "3", "--near-samples", "64"};

int bake(const Meshes& m, const std::vector<std::string>& options, const char* output, vc_bake_result** out,
         std::string* error = nullptr) {
  std::vector<const char*> words;
  for (const std::string& w : options) words.push_back(w.c_str());
  words.push_back(nullptr);
  const std::vector<vc_bake_object> objects = m.objects();
  char message[512] = "";
  const int code = vc_bake(objects.data(), objects.size(), words.data(), output, nullptr, nullptr, out, message,
                           sizeof message);
  if (error) *error = message;
  return code;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(BakeApi, GivesTheBytesOfABakeOfTheSameSceneFromAFile) {
  const Meshes m = office();
  const std::string obj = test::temp_path("api_office.obj"), from_file = test::temp_path("api_file.pvs");
  test::write_file(obj, m.obj());
  std::vector<std::string> args = {obj, "-o", from_file};
  args.insert(args.end(), kOptions.begin(), kOptions.end());
  pipeline::bake(cli::bake_options_from_args(args).config(true), [](const std::string&) {});
  const std::string want = file_bytes(from_file);
  ASSERT_GT(want.size(), 32u);

  vc_bake_result* r = nullptr;
  std::string error;
  const std::string written = test::temp_path("api_written.pvs");
  ASSERT_EQ(bake(m, kOptions, written.c_str(), &r, &error), 0) << error;
  size_t size = 0;
  const char* bytes = static_cast<const char*>(vc_bake_result_bytes(r, &size));
  EXPECT_EQ(std::string(bytes, size), want) << "vc_bake differs from the bake of the same scene as an OBJ";
  EXPECT_EQ(file_bytes(written), want) << "the file vc_bake wrote differs from the bytes it returned";
  EXPECT_EQ(vc_bake_result_cells(r), 12u);
  const nlohmann::json report = nlohmann::json::parse(vc_bake_result_report(r));
  EXPECT_EQ(report["cells"], 12);

  // The runtime opens the bytes from memory: the same cells and objects.
  vc_pvs* pvs = nullptr;
  ASSERT_EQ(vc_pvs_open_memory(bytes, size, 0, &pvs, nullptr, 0), 0);
  EXPECT_EQ(vc_pvs_cell_count(pvs), 12u);
  EXPECT_EQ(vc_pvs_object_count(pvs), m.names.size());
  EXPECT_STREQ(vc_pvs_object_name(pvs, 1), "object_1");
  vc_pvs_close(pvs);
  vc_bake_result_free(r);

  // Without an output nothing is written, and the bytes are the same.
  ASSERT_EQ(bake(m, kOptions, nullptr, &r, &error), 0) << error;
  EXPECT_EQ(std::string(static_cast<const char*>(vc_bake_result_bytes(r, &size)), size), want);
  vc_bake_result_free(r);
}

// The config struct binds fields, parsing nothing: its defaults are the library's, and a bake
// with fields set gives the bytes of the bake with the same settings as option words.
TEST(BakeApi, TheConfigStructIsTheLibrarysDefaultAndBakesAsTheWords) {
  const vc_bake_config d = vc_bake_config_default();
  const pipeline::BakeConfig library;
  EXPECT_EQ(d.samples, library.sampling.samples);
  EXPECT_EQ(d.near_samples, library.near.rays_per_object);
  EXPECT_EQ(d.play_space != 0, library.play_space_where_known);
  EXPECT_EQ(d.cells, 0u);
  EXPECT_EQ(d.memory_bytes, 0u);
  const Meshes m = office();
  vc_bake_result* words = nullptr;
  std::string error;
  ASSERT_EQ(bake(m, kOptions, nullptr, &words, &error), 0) << error;
  vc_bake_config c = vc_bake_config_default();
  c.cells = 12;
  c.samples = 20000;
  c.agvs_samples = 40000;
  c.seed = 3;
  c.near_samples = 64;
  const std::vector<vc_bake_object> objects = m.objects();
  vc_bake_result* fields = nullptr;
  char message[512] = "";
  ASSERT_EQ(vc_bake_with_config(objects.data(), objects.size(), &c, nullptr, nullptr, nullptr, &fields, message,
                                sizeof message),
            0)
      << message;
  size_t a = 0, b = 0;
  const char* wa = static_cast<const char*>(vc_bake_result_bytes(words, &a));
  const char* fb = static_cast<const char*>(vc_bake_result_bytes(fields, &b));
  EXPECT_EQ(std::string(wa, a), std::string(fb, b)) << "the config struct bakes otherwise than the words";
  vc_bake_result_free(fields);
  // The check can fail: another seed gives other bytes.
  c.seed = 4;
  ASSERT_EQ(vc_bake_with_config(objects.data(), objects.size(), &c, nullptr, nullptr, nullptr, &fields, message,
                                sizeof message),
            0)
      << message;
  EXPECT_NE(std::string(wa, a), std::string(static_cast<const char*>(vc_bake_result_bytes(fields, &b)), b));
  vc_bake_result_free(fields);
  vc_bake_result_free(words);
  // No budget, or two: an error naming it, code 2.
  c.cells = 0;
  EXPECT_EQ(vc_bake_with_config(objects.data(), objects.size(), &c, nullptr, nullptr, nullptr, &fields, message,
                                sizeof message),
            2);
  EXPECT_NE(std::string(message).find("budget"), std::string::npos) << message;
  // ... named as the struct's fields, not as the command line's flags.
  EXPECT_NE(std::string(message).find("cells (vc_bake_config)"), std::string::npos) << message;
  EXPECT_NE(std::string(message).find("memory_bytes (vc_bake_config)"), std::string::npos) << message;
  EXPECT_EQ(std::string(message).find("--"), std::string::npos) << message;
  EXPECT_EQ(vc_bake_with_config(objects.data(), objects.size(), nullptr, nullptr, nullptr, nullptr, &fields, message,
                                sizeof message),
            1);
}

/// Two boxes with a pane between them, the view space on the left: the right box is seen only
/// when the pane is see-through, and the pane is seen either way, although it stands outside
/// the view box (a see-through object is looked for along the whole line of sight). So is a
/// see-through fog sheet behind the view space, with nothing beyond it: lines of sight that
/// end there see nothing at that end.
TEST(BakeApi, SeeThroughObjectsHideNothing) {
  Meshes m;
  const std::vector<uint32_t> faces = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                       1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  for (double x : {0.0, 4.0}) {
    m.names.push_back(x == 0 ? "left" : "right");
    m.vertices.push_back({x, 0, 0, x + 1, 0, 0, x + 1, 1, 0, x, 1, 0, x, 0, 1, x + 1, 0, 1, x + 1, 1, 1, x, 1, 1});
    m.indices.push_back(faces);
    m.see_through.push_back(0);
  }
  m.names.push_back("glass");
  m.vertices.push_back({2, -5, -5, 2, 6, -5, 2, 6, 6, 2, -5, 6});
  m.indices.push_back({0, 1, 2, 0, 2, 3});
  m.see_through.push_back(0);
  m.names.push_back("fog");
  m.vertices.push_back({-3, -5, -5, -3, 6, -5, -3, 6, 6, -3, -5, 6});
  m.indices.push_back({0, 2, 1, 0, 3, 2});
  m.see_through.push_back(1);
  const std::vector<std::string> options = {"--cells", "2", "--samples", "20000", "--agvs-samples", "20000",
                                            "--view-box", "-1,-2,-1,1.9,3,2", "--near-samples", "0"};
  for (int see_through : {0, 1}) {
    m.see_through[2] = see_through;
    vc_bake_result* r = nullptr;
    std::string error;
    ASSERT_EQ(bake(m, options, nullptr, &r, &error), 0) << error;
    size_t size = 0;
    const void* bytes = vc_bake_result_bytes(r, &size);
    vc_pvs* pvs = nullptr;
    ASSERT_EQ(vc_pvs_open_memory(bytes, size, 0, &pvs, nullptr, 0), 0);
    bool right_seen = false, glass_seen = false, fog_seen = false;
    for (uint32_t c = 0; c < vc_pvs_cell_count(pvs); ++c) {
      right_seen |= vc_pvs_cell_sees(pvs, static_cast<int32_t>(c), 1) == 1;
      glass_seen |= vc_pvs_cell_sees(pvs, static_cast<int32_t>(c), 2) == 1;
      fog_seen |= vc_pvs_cell_sees(pvs, static_cast<int32_t>(c), 3) == 1;
    }
    EXPECT_TRUE(glass_seen) << "see_through " << see_through;
    EXPECT_TRUE(fog_seen) << "see_through " << see_through;
    EXPECT_EQ(right_seen, see_through == 1) << "see_through " << see_through;
    vc_pvs_close(pvs);
    vc_bake_result_free(r);
  }
}

TEST(BakeApi, RefusesBadArgumentsWithAMessageAndKeepsEarlierFiles) {
  Meshes m = office();
  const std::string path = test::temp_path("api_kept.pvs");
  test::write_file(path, "an earlier file");
  vc_bake_result* r = reinterpret_cast<vc_bake_result*>(&m);  // must be reset to NULL
  std::string error;
  EXPECT_EQ(bake(m, {"--samples", "1000"}, path.c_str(), &r, &error), 2);
  EXPECT_EQ(r, nullptr);
  EXPECT_NE(error.find("budget"), std::string::npos) << error;
  EXPECT_EQ(bake(m, {"--cells", "4", "--no-such-option"}, path.c_str(), &r, &error), 2);
  EXPECT_NE(error.find("--no-such-option"), std::string::npos) << error;
  EXPECT_EQ(bake(m, {"--cells", "4", "-o", "x.pvs"}, path.c_str(), &r, &error), 1);
  EXPECT_NE(error.find("-o is not an option here"), std::string::npos) << error;
  m.indices[2][4] = 1000;
  EXPECT_EQ(bake(m, kOptions, path.c_str(), &r, &error), 2);
  EXPECT_NE(error.find("object 2 (object_2): triangle 1 has vertex index 1000"), std::string::npos) << error;
  m = office();
  m.vertices[0][0] = std::nan("");
  EXPECT_EQ(bake(m, kOptions, path.c_str(), &r, &error), 2);
  EXPECT_NE(error.find("NaN"), std::string::npos) << error;
  EXPECT_EQ(file_bytes(path), "an earlier file");
  EXPECT_EQ(vc_bake(nullptr, 3, nullptr, nullptr, nullptr, nullptr, &r, nullptr, 0), 1);
  char small[8];
  EXPECT_EQ(vc_bake(nullptr, 0, nullptr, nullptr, nullptr, nullptr, nullptr, small, sizeof small), 1);
  EXPECT_EQ(std::string(small), "vc_bake");  // truncated, NUL-terminated
}

// bake.h promises that an object's id is its position in the array: an object with no triangles
// (or only degenerate ones) keeps its id, and the ids after it do not shift (issue 67: they
// did). And a missing output directory is an error before the bake, not after it.
TEST(BakeApi, ObjectIdsArePositionsAlsoPastAnEmptyObject) {
  Meshes m = office();
  const size_t n = m.names.size();
  m.names.insert(m.names.begin() + 1, "empty");
  m.vertices.insert(m.vertices.begin() + 1, std::vector<double>{});
  m.indices.insert(m.indices.begin() + 1, std::vector<uint32_t>{});
  m.see_through.insert(m.see_through.begin() + 1, 0);
  m.names.insert(m.names.begin() + 3, "flat");  // one triangle with three equal corners
  m.vertices.insert(m.vertices.begin() + 3, std::vector<double>{1, 1, 1});
  m.indices.insert(m.indices.begin() + 3, std::vector<uint32_t>{0, 0, 0});
  m.see_through.insert(m.see_through.begin() + 3, 0);
  vc_bake_result* r = nullptr;
  std::string error;
  ASSERT_EQ(bake(m, kOptions, nullptr, &r, &error), 0) << error;
  size_t size = 0;
  const void* bytes = vc_bake_result_bytes(r, &size);
  vc_pvs* p = nullptr;
  ASSERT_EQ(vc_pvs_open_memory(bytes, size, 0, &p, nullptr, 0), 0);
  EXPECT_EQ(vc_pvs_object_count(p), n + 2);
  std::vector<uint32_t> seen;
  for (uint32_t c = 0; c < vc_pvs_cell_count(p); ++c) {
    const uint32_t* list = nullptr;
    const size_t count = vc_pvs_cell_objects(p, static_cast<int32_t>(c), &list);
    seen.insert(seen.end(), list, list + count);
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1u), 0);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 3u), 0);
  EXPECT_LT(*std::max_element(seen.begin(), seen.end()), n + 2);
  vc_pvs_close(p);
  vc_bake_result_free(r);
  const std::string missing = test::temp_path("no_such_dir/x.pvs");
  EXPECT_EQ(bake(m, {"--cells", "4", "--samples", "1000000000"}, missing.c_str(), &r, &error), 2);
  EXPECT_NE(error.find("does not exist"), std::string::npos) << error;
}

}  // namespace
}  // namespace viewcells

namespace viewcells {
namespace {

/// What decides a bake in a config, as words, field by field (progress flags and callbacks
/// aside): two configs that print the same bake the same.
std::string describe(const pipeline::BakeConfig& c) {
  std::ostringstream k;
  k << "scene " << c.scene.path << ' ' << static_cast<int>(c.scene.grouping) << ' ' << c.scene.robust << '\n';
  const FloorSpaceConfig& f = c.scene.floors;
  k << "floors " << f.metres_per_unit << ' ' << f.cell << ' ' << f.walk_normal << ' ' << f.player_height << ' ' << f.step
    << ' ' << f.eye_low << ' ' << f.eye_high << ' ' << f.min_region << ' ' << f.start_points.size() << ' '
    << f.only_from_starts << ' ' << f.region_margin << '\n';
  const SamplerConfig& s = c.sampling;
  k << "sampling " << s.samples << ' ' << s.target_segments << ' ' << s.seed << ' ' << static_cast<int>(s.empty_space)
    << ' ' << s.max_recasts << ' ' << s.batch_size << ' ' << s.view_box.empty() << '\n';
  k << "model " << c.model.a << ' ' << c.model.b << ' ' << c.model.c << ' ' << c.model.screen_width << 'x'
    << c.model.screen_height << ' ' << c.model.fov_degrees << '\n';
  const SubdivisionConfig& d = c.subdivision;
  k << "subdivision " << static_cast<int>(d.strategy) << ' ' << d.max_cells << ' ' << d.max_axis_candidates << ' '
    << d.exact_candidates << ' ' << static_cast<int>(d.geometry_aligned) << ' ' << d.ga_candidates << ' '
    << d.min_reduction << ' ' << d.stagnation_steps << ' ' << d.seed << ' ' << d.density.enabled << ' '
    << d.play_space << '\n';
  k << "play_space_where_known " << c.play_space_where_known << '\n';
  if (c.merge_agvs)
    k << "merge_agvs " << c.merge_agvs->seed << ' ' << c.merge_agvs->max_samples << ' ' << c.merge_agvs->pixel_error
      << ' ' << c.merge_agvs->mutation_lanes << ' ' << c.merge_agvs->batch_size << '\n';
  else
    k << "merge on the construction samples\n";
  k << "budget " << c.cells << ' ' << c.memory << ' ' << c.memory_of_lists << '\n';
  const AgvsConfig& a = c.agvs;
  k << "agvs " << a.seed << ' ' << a.batch_size << ' ' << a.max_samples << ' ' << a.max_seconds << ' ' << a.pixel_error
    << ' ' << a.mutation_lanes << ' ' << a.min_share << ' ' << static_cast<int>(a.empty_space) << '\n';
  k << "time " << c.max_seconds << '\n';
  k << "measure " << c.measure_cameras << ' ' << static_cast<int>(c.cameras.placement) << ' ' << c.cameras.seed << ' '
    << c.frame.width << 'x' << c.frame.height << ' ' << c.measured_error << ' ' << c.holes << '\n';
  k << "frames " << c.frame_samples << ' ' << c.sample_frame.width << 'x' << c.sample_frame.height << ' '
    << c.frame_rounds << '\n';
  k << "near " << c.near.rays_per_object << ' ' << c.near.rounds << ' ' << c.near.distance << ' ' << c.near_eyes
    << '\n';
  k << "hidden " << c.prove_hidden << ' ' << c.conservative << ' ' << c.hidden_max_steps << ' ' << c.aimed_rays
    << '\n';
  k << "output " << c.output << ' ' << c.work_dir << ' ' << c.checkpoint_seconds << '\n';
  return k.str();
}

// The library decides: `viewcells bake SCENE -o OUT` (no other option) is BakeConfig{} with the
// scene and output, field for field, both resolved the same way (what depends on the budget and
// the stop rule: pipeline::resolve).
TEST(BakeDefaults, AnEmptyCommandLineIsTheLibrarysDefault) {
  pipeline::BakeConfig library;
  library.scene.path = "level.obj";
  library.output = "level.pvs";
  library.cells = 100;
  const pipeline::BakeConfig command =
      cli::bake_options_from_args({"level.obj", "-o", "level.pvs", "--cells", "100"}).config(true);
  EXPECT_EQ(describe(pipeline::resolve(command)), describe(pipeline::resolve(library)));
  // The check can fail: one option given changes the words.
  const pipeline::BakeConfig other =
      cli::bake_options_from_args({"level.obj", "-o", "level.pvs", "--cells", "100", "--near-samples", "0"}).config(true);
  EXPECT_NE(describe(pipeline::resolve(other)), describe(pipeline::resolve(library)));
}

/// A value of `o` other than its default that its check takes (texts: one that parses).
std::string sample_value(const pipeline::BakeOption& o) {
  using Kind = pipeline::BakeOption::Kind;
  const std::string fallback = o.show ? o.show(pipeline::BakeOptions{}) : "";
  std::vector<std::string> candidates;
  if (o.kind == Kind::kWhole) candidates = {"3", "2", "5", "1", "0"};
  if (o.kind == Kind::kNumber) candidates = {"0.25", "0.5", "2", "45"};
  if (o.kind == Kind::kText || o.kind == Kind::kTexts) {
    const std::map<std::string, std::string> texts = {
        {"--objects", "triangles"},       {"--view-box", "0,0,0,1,1,1"}, {"--empty-space", "off"},
        {"--memory", "1M"},               {"--memory-of", "lists"},      {"--screen", "800x600"},
        {"--density-band", "0,2"},        {"--merge-pvs", "samples"},    {"--work", "work"},
        {"--holes", "2%"},                {"--frame-size", "64x48"},     {"--measure-size", "32x24"},
        {"--start", "1,2,3"},             {"--eye-band", "1,2"}};
    const auto it = texts.find(o.flag);
    if (it != texts.end()) candidates = {it->second};
  }
  for (const std::string& c : candidates)
    if (o.check(c).empty() && c != fallback) return c;
  return "";
}

// Every option of the library's table, one at a time: the command line (CLI11, whose bake is
// built from the table) and the library's own word parser (vc_bake's) make the same config, and
// it differs from the one without the option (an option that changed nothing, or that one
// parser dropped, fails here). Python's keywords go through the same table (set_bake_option).
TEST(BakeDefaults, EveryOptionOfTheTableMeansTheSameToBothParsers) {
  using Kind = pipeline::BakeOption::Kind;
  const std::vector<std::string> base = {"level.obj", "-o", "level.pvs"};
  const std::string plain = describe(pipeline::parse_bake_words({"level.obj", "-o", "level.pvs", "--cells", "100"}).config(true));
  size_t tried = 0;
  for (const pipeline::BakeOption& o : pipeline::bake_option_table()) {
    std::vector<std::string> words = base;
    if (o.flag != "--memory" && o.flag != "--cells") words.insert(words.end(), {"--cells", "100"});
    if (o.flag == "--merge-samples" || o.flag == "--merge-pixel-error") words.insert(words.end(), {"--merge-pvs", "agvs"});
    if (o.kind == Kind::kFlag) {
      words.push_back(o.flag);
    } else {
      const std::string value = sample_value(o);
      ASSERT_FALSE(value.empty()) << o.flag << ": give the test a value for it";
      words.insert(words.end(), {o.flag, value});
    }
    SCOPED_TRACE(o.flag);
    const std::string command = describe(cli::bake_options_from_args(words).config(true));
    const std::string library = describe(pipeline::parse_bake_words(words).config(true));
    EXPECT_EQ(command, library);
    EXPECT_NE(library, plain) << o.flag << " changed nothing in the config";
    EXPECT_TRUE(pipeline::find_bake_option(o.keyword) == &o) << o.keyword;
    ++tried;
  }
  EXPECT_GT(tried, 60u);
  // A negation given a truth value turns the option off for any way of writing true.
  for (const char* on : {"true", "1", "on", "yes"})
    EXPECT_FALSE(pipeline::parse_bake_words(
                     {"level.obj", "-o", "level.pvs", "--prove-hidden", std::string("--no-prove-hidden=") + on})
                     .bound.prove_hidden)
        << on;
  EXPECT_THROW(pipeline::parse_bake_words({"level.obj", "-o", "level.pvs", "--no-prove-hidden=maybe"}), Error);
  // A negation, and the "=" form, in both.
  for (const std::vector<std::string>& extra : {std::vector<std::string>{"--prove-hidden", "--no-prove-hidden"},
                                                 std::vector<std::string>{"--prove-hidden", "--no-prove-hidden=1"},
                                                 std::vector<std::string>{"--cells=7"}}) {
    std::vector<std::string> words = {"level.obj", "-o", "level.pvs", "--cells", "100"};
    if (extra.front() == "--cells=7") words = {"level.obj", "-o", "level.pvs"};
    words.insert(words.end(), extra.begin(), extra.end());
    EXPECT_EQ(describe(cli::bake_options_from_args(words).config(true)),
              describe(pipeline::parse_bake_words(words).config(true)));
  }
}

// Both parsers refuse the same words, each naming the option.
TEST(BakeDefaults, BothParsersRefuseWhatTheTableRefuses) {
  const std::vector<std::vector<std::string>> bad = {
      {"--cells", "0"}, {"--cells", "4", "--memory", "1M"}, {"--seed", "-1"}, {"--min-share", "2"},
      {"--merge-pvs", "both"}, {"--cells", "4", "--no-such-option"}, {"--cells", "4", "--ga", "--no-ga"}};
  for (const auto& extra : bad) {
    std::vector<std::string> words = {"level.obj", "-o", "level.pvs"};
    words.insert(words.end(), extra.begin(), extra.end());
    std::string joined;
    for (const std::string& w : extra) joined += w + " ";
    SCOPED_TRACE(joined);
    EXPECT_THROW(cli::bake_options_from_args(words).config(true), Error);
    try {
      pipeline::parse_bake_words(words).config(true);
      ADD_FAILURE() << "the library took it";
    } catch (const Error& e) {
      const std::string named = extra.size() > 2 && extra[0] == "--cells" ? extra[2] : extra[0];
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  }
  // Without a budget: the library's message, for both.
  EXPECT_THROW(cli::bake_options_from_args({"level.obj", "-o", "level.pvs"}).config(true), Error);
  EXPECT_THROW(pipeline::parse_bake_words({"level.obj", "-o", "level.pvs"}).config(true), Error);
}

}  // namespace
}  // namespace viewcells
