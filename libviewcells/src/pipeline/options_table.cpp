// The table of the bake's options (pipeline/options.h): each option's flag, help, check, shown
// default and the field of BakeOptions it sets, in the order `viewcells bake --help` lists them.
#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <type_traits>

#include "viewcells/pipeline/options.h"

namespace viewcells::pipeline {

namespace {

using Kind = BakeOption::Kind;
using Check = OptionCheck;

/// The number rules, by the names the table reads best with.
ValueRule any_number() { return any_number_rule(); }
ValueRule positive() { return positive_rule(); }
ValueRule non_negative() { return non_negative_rule(); }
ValueRule in_range(double lo, double hi) { return range_rule(lo, hi); }

std::optional<bool> truth(const std::string& text) {
  if (text == "true" || text == "1" || text == "on" || text == "yes") return true;
  if (text == "false" || text == "0" || text == "off" || text == "no") return false;
  return std::nullopt;
}

/// A field of BakeOptions, for the table's setters: FIELD(cells.max_cells).
#define FIELD(member) [](BakeOptions& o) -> auto& { return o.member; }

template <class Get>
BakeOption whole(const std::string& flag, Get get, uint64_t lo, uint64_t hi, std::string help, bool show = false) {
  BakeOption o;
  o.flag = flag;
  o.kind = Kind::kWhole;
  const ValueRule rule = whole_rule(lo, hi);
  o.type = rule.type;
  o.help = std::move(help);
  o.show_default = show;
  o.check = rule.check;
  o.set = [get](BakeOptions& b, const std::string& text) {
    using T = std::remove_reference_t<decltype(get(b))>;
    get(b) = static_cast<T>(std::stoull(text));
  };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return std::to_string(get(copy));
  };
  return o;
}

template <class Get>
BakeOption number(const std::string& flag, Get get, const ValueRule& rule, std::string help, bool show = false) {
  BakeOption o;
  o.flag = flag;
  o.kind = Kind::kNumber;
  o.type = rule.type;
  o.help = std::move(help);
  o.show_default = show;
  o.check = rule.check;
  o.set = [get](BakeOptions& b, const std::string& text) { get(b) = std::stod(text); };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return option_number(get(copy));
  };
  return o;
}

/// Text parsed when the bake's config is made (sizes, boxes, bytes), or one of `members`.
template <class Get>
BakeOption text(const std::string& flag, Get get, std::string help, bool show = false,
                std::vector<std::string> members = {}) {
  BakeOption o;
  o.flag = flag;
  o.kind = Kind::kText;
  o.help = std::move(help);
  o.show_default = show;
  if (!members.empty()) {
    std::string list, said;
    for (size_t i = 0; i < members.size(); ++i) {
      list += (i ? "," : "") + members[i];
      said += (i == 0 ? "" : i + 1 == members.size() ? " or " : ", ") + members[i];
    }
    o.type = "{" + list + "}";
    o.check = [members, said](const std::string& t) {
      return std::find(members.begin(), members.end(), t) != members.end() ? "" : refused_value(t, said);
    };
  } else {
    o.check = [](const std::string&) { return std::string(); };
  }
  o.set = [get](BakeOptions& b, const std::string& t) { get(b) = t; };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return std::string(get(copy));
  };
  return o;
}

/// On when given (or given "true"); `negation` turns it off.
template <class Get>
BakeOption flag(const std::string& name, Get get, std::string help, const std::string& negation = "") {
  BakeOption o;
  o.flag = name;
  o.negation = negation;
  o.kind = Kind::kFlag;
  o.help = std::move(help);
  o.check = [](const std::string& t) { return truth(t) ? "" : refused_value(t, "true or false"); };
  o.set = [get](BakeOptions& b, const std::string& t) { get(b) = *truth(t); };
  o.show = [get](const BakeOptions& b) {
    BakeOptions copy = b;
    return std::string(get(copy) ? "true" : "false");
  };
  return o;
}

BakeOption excluding(BakeOption o, std::vector<std::string> flags) {
  o.excludes = std::move(flags);
  return o;
}

BakeOption in_group(BakeOption o, const std::string& group) {
  o.group = group;
  return o;
}

/// The scene and its sampling (also sample, build and compare's).
void sampling_options(std::vector<BakeOption>& t) {
  t.push_back(excluding(whole("--samples", FIELD(sampling.samples), 1, kMaxSamples, "Number of samples (two rays each)", true),
                        {"--segments"}));
  t.push_back(excluding(whole("--segments", FIELD(sampling.segments), 1, kMaxSamples,
                              "Sample until this many valid segments exist (instead of --samples)"),
                        {"--samples"}));
  t.push_back(whole("--seed", FIELD(sampling.seed), 0, UINT64_MAX, "Random seed (same seed, same result for any --threads)",
                    true));
  t.push_back(text("--objects", FIELD(sampling.objects),
                   "Object grouping: auto | groups | components | triangles | nodes | meshes (nodes and meshes: glTF, "
                   "FBX and other formats read through Assimp; auto there means nodes)",
                   true));
  t.push_back(text("--view-box", FIELD(sampling.view_box),
                   "View space box xmin,ymin,zmin,xmax,ymax,zmax (default: scene bounds)"));
  t.push_back(text("--empty-space", FIELD(sampling.empty_space),
                   "Empty view space detection: auto (only for closed, outward-oriented scenes) | on | off", true));
  t.push_back(whole("--max-recasts", FIELD(sampling.max_recasts), 0, 1000, "Re-casts per sample when empty space detection is on",
                    true));
  t.push_back(flag("--fast", FIELD(sampling.fast), "Embree without robust mode (faster, may leak through edges)"));
}

/// The budget.
void budget_options(std::vector<BakeOption>& t) {
  t.push_back(excluding(whole("--cells", FIELD(bound.cells), 1, kMaxCells, "Budget: this many view cells"), {"--memory"}));
  t.push_back(excluding(text("--memory", FIELD(memory),
                             "Budget: a .pvs file of at most this many bytes (K, M, G allowed); the file written is "
                             "measured, and the cells are merged further until it fits"),
                        {"--cells"}));
  t.push_back(text("--memory-of", FIELD(memory_of),
                   "What --memory counts: file (the whole .pvs) or lists (the visible sets alone as an engine's compact "
                   "handle holds them: the coded lists and 8 bytes a hierarchy node, without point location and object "
                   "names; what stands against a map compiler's vis rows)",
                   true, {"file", "lists"}));
  t.push_back(whole("--max-cells", FIELD(cells.max_cells), 1, kMaxCells,
                    "Elementary cells to build before merging (default: 4 x --cells, or 4096 with --memory)"));
}

/// The subdivision and its cost model (also build's).
void subdivision_options(std::vector<BakeOption>& t) {
  t.push_back(excluding(flag("--no-ga", FIELD(cells.no_ga), "No geometry-aligned split candidates"), {"--ga"}));
  t.push_back(excluding(flag("--ga", FIELD(cells.ga), "Geometry-aligned candidates even for mostly axis-aligned scenes"),
                        {"--no-ga"}));
  t.push_back(whole("--ga-candidates", FIELD(cells.ga_candidates), 0, UINT32_MAX,
                    "Geometry-aligned planes tried per cell at most", true));
  t.push_back(whole("--axis-candidates", FIELD(cells.axis_candidates), 1, UINT32_MAX,
                    "Axis-aligned positions tried per axis and cell at most", true));
  t.push_back(flag("--exact-candidates", FIELD(cells.exact_candidates),
                   "Axis-aligned positions as the paper draws them: a uniform random subset of the distinct "
                   "segment-end coordinates of each cell, which needs them all sorted (about 3x slower subdivision on "
                   "large scenes). Default: random segment ends until --axis-candidates distinct ones, so that "
                   "coordinates where many segments end (walls) are likelier; both evaluate their positions exactly"));
  t.push_back(number("--min-reduction", FIELD(cells.min_reduction), non_negative(),
                     "Stop when splits reduce the cost by less than this share of the initial cost for 50 splits running",
                     true));
  t.push_back(number("--cost-a", FIELD(cells.cost_a), any_number(),
                     "Render cost model: minimum cost of an object (r = max(a, b * triangles))", true));
  t.push_back(number("--cost-b", FIELD(cells.cost_b), any_number(), "Render cost model: cost per triangle", true));
  t.push_back(number("--cost-c", FIELD(cells.cost_c), any_number(),
                     "Render cost model: cost per projected pixel, estimated per cell from its corners and centre "
                     "(0: no pixel term, nothing estimated)",
                     true));
  t.push_back(text("--screen", FIELD(cells.screen), "Screen WIDTHxHEIGHT the pixel term assumes (with --cost-c)", true));
  t.push_back(number("--fov", FIELD(cells.fov), any_number(),
                     "Horizontal field of view in degrees the pixel term assumes (with --cost-c)", true));
  t.push_back(text("--density-band", FIELD(cells.density_band),
                   "Viewpoint density zlo,zhi[,outside]: weight 1 between the heights, outside (default 0.1) elsewhere"));
  t.push_back(excluding(flag("--play-space", FIELD(cells.play_space),
                             "Quake 3 maps: weigh cells by their volume where a player's eye can be (non-solid leaves "
                             "reachable from the spawn points, at most 112 units above a walkable floor) instead of all "
                             "non-solid space, so merging spends the cells where players are (bake: the default on a Quake 3 "
                             "map unless --density-band or --view-box is given)"),
                        {"--no-play-space"}));
  t.push_back(excluding(flag("--no-play-space", FIELD(cells.no_play_space),
                             "Quake 3 maps: weigh cells by their volume in all of the map's non-solid space, not the "
                             "play space"),
                        {"--play-space"}));
}

/// Merging (also build's).
void merge_options(std::vector<BakeOption>& t) {
  t.push_back(text("--merge-pvs", FIELD(merge.pvs),
                   "What merging decides on: agvs (the elementary cells' PVSs from the construction samples united with "
                   "an AGVS run over the cells, and greedy merging started from the subdivision's own cut that "
                   "held-out samples score best: a second AGVS run and four times as many random samples as the "
                   "construction drew, no count rated worse than the subdivision's own cut by either (0.2% from 16 "
                   "cells up and 2% below for histories within refined blocks at low counts); the choice is made again "
                   "below each barrier where the cut is the subdivision's) or samples (greedy merging on the "
                   "construction samples' PVSs alone: a few hundred per cell, whose gaps it fits)",
                   true, {"agvs", "samples"}));
  t.push_back(whole("--merge-samples", FIELD(merge.samples), 1, kMaxSamples,
                    "AGVS samples of each of the two runs over the elementary cells (one to merge on, one held out to "
                    "choose where greedy merging starts; default, without --merge-pixel-error: --samples)"));
  t.push_back(number("--merge-pixel-error", FIELD(merge.pixel_error), positive(),
                     "Run each AGVS run over the elementary cells until its estimated pixel error (of 1024x1024) is at "
                     "most this"));
  t.push_back(whole("--merge-mutation-lanes", FIELD(merge.lanes), 1, 65536,
                    "Mutation lanes of those AGVS runs (as pvs --mutation-lanes: more lanes spread the mutations over "
                    "threads and cluster ranks; the result depends on it, not on the threads or ranks)",
                    true));
}

/// The PVSs' AGVS (also pvs's, where --agvs-time and --agvs-samples are --time and --samples).
void agvs_options(std::vector<BakeOption>& t) {
  t.push_back(number("--pixel-error", FIELD(agvs.pixel_error), positive(),
                     "Stop when the estimated pixel error (pixels of a 1024x1024 image that differ) is at most this"));
  t.push_back(number("--agvs-time", FIELD(agvs.max_seconds), positive(), "Stop AGVS after this many seconds of sampling"));
  t.push_back(whole("--agvs-samples", FIELD(agvs.max_samples), 1, kMaxSamples,
                    "Stop after this many AGVS samples (checked between batches: a run may pass it by less than a "
                    "batch)"));
  t.push_back(whole("--batch", FIELD(agvs.batch_size), 1, 100'000'000, "Samples per batch", true));
  t.push_back(whole("--mutation-lanes", FIELD(agvs.mutation_lanes), 1, 65536,
                    "AGVS: independent lanes of mutation candidates, each with its own random stream and its share of "
                    "the buffer. Lanes are drawn and fed in parallel, on a cluster each by its own rank: give at least "
                    "as many as the cores of all nodes for a bake that scales. The result depends on it, not on the "
                    "threads or ranks",
                    true));
  t.push_back(number("--min-share", FIELD(agvs.min_share), in_range(0, 1),
                     "AGVS: share of every batch kept for view space-direction samples whatever their weight; they are "
                     "the pixel error estimator's camera rays (more: a finer estimate, fewer samples for the "
                     "mutations)",
                     true));
}

/// The bake's own: its time, work directory, stops, frame and near-object samples, the proof.
void bake_own_options(std::vector<BakeOption>& t) {
  t.push_back(number("--time", FIELD(bound.max_seconds), positive(),
                     "Bound the whole bake to this many seconds: each of the merge's two AGVS runs stops at a quarter "
                     "of it, the PVSs' AGVS at three quarters of what is left, the near-object samples when it runs "
                     "out (a hierarchy that uses it all up is an error, and with --work is kept for a rerun). "
                     "--agvs-time bounds the PVSs' AGVS alone"));
  t.push_back(text("--work", FIELD(bound.work_dir),
                   "Work directory: keeps the hierarchy and the AGVS state, so that a rerun with the same scene and "
                   "settings skips the hierarchy and continues sampling (e.g. with a smaller --pixel-error)"));
  t.push_back(number("--checkpoint", FIELD(bound.checkpoint_seconds), non_negative(),
                     "With --work: save the AGVS state this often, in seconds, so that a bake cut off continues from "
                     "there when run again (0: only at the end)",
                     true));
  t.push_back(number("--measured-error", FIELD(bound.measured_error), non_negative(),
                     "Stop AGVS once cameras measure at most this many wrong pixels per 1024x1024 frame (mean over the "
                     "cameras), instead of trusting the estimate: measured after one batch and at every doubling of "
                     "the samples (a run may sample up to twice what it needed; --time and the other limits still "
                     "apply)"));
  t.push_back(text("--holes", FIELD(holes),
                   "Stop AGVS once at most this percentage of the measuring cameras' frames shows any wrong pixel "
                   "(e.g. 1%): the holes a player sees. Measured after one batch and at every doubling of the samples "
                   "(by default 1,000 cameras of 1024x768, placed as `viewcells measure` places them), each "
                   "measurement logged with an estimate of the time left; with --measured-error both must hold; "
                   "--time still bounds the bake"));
  t.push_back(whole("--frame-samples", FIELD(bound.frame_samples), 0, 100000,
                    "After AGVS, frames as a sampler: this many cameras per view cell on average, placed as measuring "
                    "cameras are (on a Quake 3 map player eyes, pitch within 30 degrees) but from a seed of their own, "
                    "render --frame-size frames, and every object a frame shows joins its cell's PVS (0: none)"));
  t.push_back(text("--frame-size", FIELD(frame_size), "Frames of --frame-samples, WIDTHxHEIGHT", true));
  t.push_back(whole("--frame-rounds", FIELD(bound.frame_rounds), 1, 64,
                    "Rounds of --frame-samples: after the first, only the cells whose frames still added an object "
                    "get about as many frames again",
                    true));
  t.push_back(whole("--near-samples", FIELD(bound.near.rays_per_object), 0, 4096,
                    "After AGVS, near-object samples: every view cell tests each object whose box lies within "
                    "--near-distance of an object of its PVS and that it lacks, with this many rays from its "
                    "viewpoints (placed as measuring cameras are, --near-eyes a cell on average, a seed of their own) "
                    "to random points on the object; the object joins the PVS when a ray reaches it unblocked. They "
                    "close most of the holes AGVS leaves (trims and steps beside what a cell sees) for a few percent "
                    "of render cost; at most 2^31 rays in all (fewer a candidate on scenes with more). 0: none",
                    true));
  t.push_back(flag("--conservative", FIELD(bound.conservative),
                   "Ship no holes by construction: prove objects hidden through the scene's solid space (a Quake 3 "
                   "map's BSP portals, or a mesh's closed convex solids), and add every (cell, object) pair that is "
                   "neither seen by a ray nor proven hidden to the PVSs, so that no line from any point of a cell "
                   "reaches an object missing from its PVS. Costs more to render than the sampled PVSs (the report's "
                   "hidden.cost_per_frame gives both bounds); an error on a scene that can prove nothing hidden"));
  BakeOption prove = flag("--prove-hidden", FIELD(bound.prove_hidden),
                          "Sort every (cell, object) pair into proven visible, proven hidden and undecided, and report "
                          "the classes and the render cost of both bounds (the report's \"hidden\"); the PVSs written "
                          "are unchanged unless --conservative",
                          "--no-prove-hidden");
  prove.show_default = true;
  t.push_back(prove);
  t.push_back(whole("--proof-steps", FIELD(bound.hidden_max_steps), 1, 1000000000,
                    "Portals one flood of the proof may try; a flood over it keeps all it might still reach (never "
                    "less: only the bound loosens)",
                    true));
  t.push_back(whole("--aimed-rays", FIELD(bound.aimed_rays), 0, 1000000,
                    "With the proof (--prove-hidden, --conservative): rays aimed at each (view cell, object) pair it "
                    "leaves undecided, from points of the cell's empty space to points of the object, up to this many "
                    "a pair; one that arrives proves the pair visible (0: none)",
                    true));
  t.push_back(whole("--near-rounds", FIELD(bound.near.rounds), 1, 64,
                    "Rounds of --near-samples: each round tests the neighbours of what the last one added", true));
  t.push_back(whole("--near-eyes", FIELD(bound.near_eyes), 1, 100000,
                    "Viewpoints a cell has on average for --near-samples", true));
  t.push_back(number("--near-distance", FIELD(bound.near.distance), non_negative(),
                     "Objects are neighbours for --near-samples when their boxes are at most this far apart (default "
                     "1/1000 of the scene's bounding box diagonal)"));
  t.push_back(text("--measure-size", FIELD(measure_size),
                   "Frames of the measuring cameras, WIDTHxHEIGHT (default 1024x768 with --holes, else 64x48)"));
  t.push_back(whole("--measure-cameras", FIELD(bound.measure_cameras), 1, 1'000'000,
                    "Cameras that measure the PVSs, placed and counted as `viewcells measure` does (on a Quake 3 map "
                    "player eyes above floors reachable from the spawn points, else random points of the view box; "
                    "64x48 pixels, seed 1): the report gives the written file's measured pixel error (default: 5000 "
                    "with --measured-error, else none)"));
}

/// Where players stand on scenes other than Quake 3 maps (also build's, measure's, play-space's).
void floor_options(std::vector<BakeOption>& t) {
  const std::string g = "Play space from floors (scenes other than Quake 3 maps)";
  t.push_back(in_group(number("--metres-per-unit", FIELD(sampling.floors.config.metres_per_unit), positive(),
                              "Metres in one unit of the scene (default: the file's own: 1 for glTF, 1/32 for a Quake "
                              "3 map; 1 when the file does not say, e.g. OBJ)"),
                       g));
  BakeOption start;  // repeatable: each value is one more start point
  start.flag = "--start";
  start.kind = Kind::kTexts;
  start.help = "Where players start, X,Y,Z in scene units (repeatable; default: the file's spawn nodes, else every "
               "floor region of at least --min-region)";
  start.check = [](const std::string&) { return std::string(); };
  start.set = [](BakeOptions& b, const std::string& xyz) { b.sampling.floors.starts.push_back(xyz); };
  start.show = [](const BakeOptions&) { return std::string(); };
  t.push_back(in_group(start, g));
  t.push_back(in_group(flag("--only-from-starts", FIELD(sampling.floors.config.only_from_starts),
                            "With start points: only what they reach (default: also every floor region of at least "
                            "--min-region within --region-margin of it, since walking misses jump pads and "
                            "teleporters)"),
                       g));
  t.push_back(in_group(number("--region-margin", FIELD(sampling.floors.config.region_margin), non_negative(),
                              "With start points: floor regions join within this many metres (horizontally) of what "
                              "they reach",
                              true),
                       g));
  t.push_back(in_group(number("--player-height", FIELD(sampling.floors.config.player_height), positive(),
                              "Free space a standing player needs above a floor, metres", true),
                       g));
  t.push_back(in_group(number("--step", FIELD(sampling.floors.config.step), non_negative(),
                              "Highest step a player walks up, metres", true),
                       g));
  t.push_back(in_group(text("--eye-band", FIELD(sampling.floors.eye_band),
                            "Eye heights above a floor, LO,HI metres (crouch to jump; default 1,3)"),
                       g));
  t.push_back(in_group(number("--walk-normal", FIELD(sampling.floors.config.walk_normal), in_range(0.01, 1),
                              "Least z of a walkable floor's unit normal (0.7: 45.6 degrees)", true),
                       g));
  t.push_back(in_group(number("--floor-cell", FIELD(sampling.floors.config.cell), in_range(0.01, 100),
                              "Spacing of the columns of rays that find the floors, metres", true),
                       g));
  t.push_back(in_group(number("--min-region", FIELD(sampling.floors.config.min_region), non_negative(),
                              "Floor regions at least this large are starts (with start points too, unless "
                              "--only-from-starts), square metres",
                              true),
                       g));
}

std::vector<BakeOption> make_table() {
  std::vector<BakeOption> t;
  // Each group under its heading in help (the floors' options name theirs).
  auto group = [&t](void (*add)(std::vector<BakeOption>&), const char* heading) {
    const size_t from = t.size();
    add(t);
    for (size_t i = from; i < t.size(); ++i)
      if (t[i].group.empty()) t[i].group = heading;
  };
  group(sampling_options, "Scene and sampling");
  group(budget_options, "Budget");
  group(subdivision_options, "View cells: subdivision and render cost model");
  group(merge_options, "Merging");
  group(agvs_options, "PVSs by AGVS: when it stops, how it samples");
  group(bake_own_options, "The bake: time, work directory, measured stops, frame and near-object samples, the proof");
  group(floor_options, "");
  for (BakeOption& o : t) {
    o.keyword = o.flag.substr(2);
    std::replace(o.keyword.begin(), o.keyword.end(), '-', '_');
  }
  return t;
}

#undef FIELD

}  // namespace

const std::vector<BakeOption>& bake_option_table() {
  static const std::vector<BakeOption> table = make_table();
  return table;
}

}  // namespace viewcells::pipeline
