// extract, compress, recode, query, view: view cells cut from the merge history, their PVSs, a viewpoint,
// and views of them for people (a web page, glTF).
#include <iostream>
#include <memory>

#include "options.h"
#include "viewcells/core/error.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/vis/level_view.h"
#include "viewcells/pipeline/cut.h"
#include "viewcells/pipeline/play.h"
#include "viewcells/pipeline/report.h"

namespace viewcells::cli {

namespace {

struct ExtractArgs {
  std::string input, output, scene, objects = "auto";
  CutOptions cut;
  pipeline::ViewsConfig views;
};

int run_extract(const ExtractArgs& e, const Common& c) {
  check_files({e.input, e.scene}, {e.output, e.views.mesh, e.views.slice_png});
  pipeline::ExtractConfig config;
  config.hierarchy_path = e.input;
  config.cut = e.cut.rule();
  config.scene_path = e.scene;
  config.grouping = parse_grouping(e.objects);
  config.views = e.views;
  const pipeline::ExtractResult result = pipeline::extract(config, c.logger());
  write_report_to(e.output, result, c, "view cells");
  if (e.output.empty() && !e.views.any()) std::cout << pipeline::report_json(result);
  return 0;
}

struct CompressArgs {
  std::string input, output, flat, report;
  CutOptions cut;
};

int run_compress(const CompressArgs& a, const Common& c) {
  check_files({a.input}, {a.output, a.flat, a.report});
  pipeline::CompressConfig config;
  config.hierarchy_path = a.input;
  config.cut = a.cut.rule();
  config.output = a.output;
  config.flat = a.flat;
  const pipeline::CompressResult result = pipeline::compress(config, c.logger());
  write_report_to(a.report, result, c);
  return 0;
}

struct QueryArgs {
  std::string input;
  std::vector<double> point;
  bool json_out = false;
};

int run_query(const QueryArgs& q) {
  const PvsFile f = read_pvs(q.input);
  if (q.point.size() != 3) throw Error("query needs a point: X Y Z");
  const Vec3 p{q.point[0], q.point[1], q.point[2]};
  if (!is_finite(p)) throw Error("query point has non-finite coordinates");
  const int32_t cell = f.locate(p);
  if (cell < 0)
    throw Error("(" + fmt(p.x, 3) + ", " + fmt(p.y, 3) + ", " + fmt(p.z, 3) + ") is outside the view space");
  if (q.json_out) {
    std::cout << pipeline::query_json(f, p, cell);
    return 0;
  }
  const std::vector<uint32_t> pvs = f.pvs.cell_pvs(static_cast<uint32_t>(cell));
  std::cout << "cell " << cell << " of " << f.pvs.cell_count << " (" << f.rule << "): " << pvs.size() << " of "
            << f.object_count << " objects visible\n";
  for (uint32_t o : pvs) std::cout << "  " << o << (f.object_names.empty() ? "" : "  " + f.object_names[o]) << '\n';
  return 0;
}

struct RecodeArgs {
  std::string input, output;
  uint32_t format = 2;
};

int run_recode(const RecodeArgs& a, const Common& c) {
  check_files({a.input}, {a.output});
  pipeline::recode(a.input, a.output, a.format, c.logger());
  return 0;
}

struct ViewArgs {
  std::string input, scene, site, gltf, objects = "auto";
  double cost_a = CostModel{}.a, cost_b = CostModel{}.b;
  bool no_play_space = false;
  FloorOptions floors;
};

int run_view(const ViewArgs& a, const Common& c) {
  if (a.site.empty() && a.gltf.empty()) throw Error("view writes a web page (-o DIR) or glTF (--gltf FILE): give one");
  check_files({a.input, a.scene}, {a.gltf}, {a.site});
  if (!a.site.empty()) require_web_viewer();  // before any work
  CostModel model;
  model.a = a.cost_a;
  model.b = a.cost_b;
  model.validate();
  PvsFile f = read_pvs(a.input);
  const auto scene = std::make_shared<const Scene>(load_scene(a.scene, parse_grouping(a.objects)));
  LevelView view = make_level_view(std::move(f), *scene, model);
  if (!a.no_play_space) {
    pipeline::SceneSource source;
    source.path = a.scene;
    source.scene = scene;
    source.floors = a.floors.floors();
    pipeline::add_play_space(view, source, c.logger());
    c.log("viewcells: play space " + std::string(view.play_space.indices.empty() ? "" : "drawn (green): ") +
          view.play_space_rule);
  }
  if (!a.gltf.empty()) {
    write_level_gltf(a.gltf, view);
    c.log("viewcells: wrote " + a.gltf + " (" + std::to_string(view.pvs.size()) + " view cells, " +
          std::to_string(view.object_names.size()) + " objects)");
  }
  if (!a.site.empty()) {
    write_web_viewer(a.site, view);
    c.log("viewcells: wrote " + a.site + "/index.html (open it in a browser; it needs no server)");
  }
  return 0;
}

}  // namespace

void add_cut_commands(CLI::App& app, const Common& common, Commands& commands) {
  auto e = std::make_shared<ExtractArgs>();
  auto* xt = app.add_subcommand("extract", "Cut view cells from the merge history of a built hierarchy");
  xt->add_option("cells", e->input, "Hierarchy file (.vcells, built with merging)")->required();
  add_cut_options(xt, e->cut);
  xt->add_option("-o,--output", e->output, "JSON file of the view cells (default: printed)");
  add_view_options(xt, e->views, "PLY of the BSP leaves coloured by their view cell's render cost",
                   "PNG of a horizontal slice, borders between view cells");
  xt->add_option("--scene", e->scene,
                 "Draw this scene's cross-section into the slice (the scene the cells were built from)");
  xt->add_option("--objects", e->objects, "With --scene: the object grouping the cells were built with")
      ->capture_default_str();
  commands.push_back({xt, [e, &common] { return run_extract(*e, common); }});

  auto cmp = std::make_shared<CompressArgs>();
  auto* cp = app.add_subcommand("compress",
                                "Write the view cells' PVSs, compressed through the hierarchy, as a .pvs file");
  cp->add_option("cells", cmp->input, "Hierarchy file (.vcells, built with merging)")->required();
  add_cut_options(cp, cmp->cut);
  cp->add_option("-o,--output", cmp->output, "The .pvs file to write")->required();
  cp->add_option("--flat", cmp->flat, "Also write Quake-style run-length coded bit rows, to compare sizes");
  cp->add_option("--report", cmp->report, "JSON report: entries and bytes before and after");
  commands.push_back({cp, [cmp, &common] { return run_compress(*cmp, common); }});

  auto q = std::make_shared<QueryArgs>();
  auto* qy = app.add_subcommand("query", "Print the view cell containing a point and its PVS");
  qy->add_option("pvs", q->input, "A .pvs file (from compress, pvs or bake)")->required();
  qy->add_option("point", q->point, "X Y Z")->required()->expected(3);
  qy->add_flag("--json", q->json_out, "Print JSON");
  commands.push_back({qy, [q] { return run_query(*q); }});

  auto rc = std::make_shared<RecodeArgs>();
  auto* re = app.add_subcommand("recode",
                                "Rewrite a .pvs file in the current format (format 2 codes its PVS lists in 1.3-2x "
                                "fewer bytes than format 1); cells and PVSs are unchanged, checked by reading back");
  re->add_option("pvs", rc->input, "A .pvs file of any format this build reads")->required();
  re->add_option("-o,--output", rc->output, "The .pvs file to write")->required();
  re->add_option("--format", rc->format,
                 "Format to write: 2 (the current one), or 1 for engines whose runtime reader predates format 2")
      ->check(CLI::IsMember({1u, 2u}))
      ->capture_default_str();
  commands.push_back({re, [rc, &common] { return run_recode(*rc, common); }});

  auto v = std::make_shared<ViewArgs>();
  auto* vw = app.add_subcommand(
      "view",
      "Look at view cells and what they see: a static web page (three.js; the scene, the cells coloured by render "
      "cost or PVS size, a clicked cell's PVS lit and the rest dimmed) and/or a glTF file for Blender or an engine");
  vw->add_option("pvs", v->input, "A .pvs file (from compress, pvs or bake)")->required();
  vw->add_option("--scene", v->scene, "The scene the .pvs file was made for")->required();
  vw->add_option("-o,--output", v->site, "Directory to write the web page into (index.html, viewer.js, data.js)");
  vw->add_option("--gltf", v->gltf,
                 "Binary glTF (.glb) to write: the scene's objects, and one node per view cell coloured by render "
                 "cost with its PVS in the node's extras");
  vw->add_option("--objects", v->objects, "Object grouping used when the .pvs file was made")->capture_default_str();
  vw->add_option("--cost-a", v->cost_a, "Render cost model for the colours: r = max(a, b * triangles)")
      ->capture_default_str();
  vw->add_option("--cost-b", v->cost_b, "Render cost model: cost per triangle")->capture_default_str();
  vw->add_flag("--no-play-space", v->no_play_space,
               "Do not draw the play space (scenes other than Quake 3 maps: the floors players are assumed to stand "
               "on, found as bake finds them; give bake's floor options again if the bake had any)");
  add_floor_options(vw, v->floors);
  commands.push_back({vw, [v, &common] { return run_view(*v, common); }});
}

}  // namespace viewcells::cli
