// How low can a merge of a tree's leaves go at a few cells? An optimistic reference for the
// merging issue's low-count goals (AV-M at most 0.8 x KD-CASM on the office from 16 cells up):
// the leaves of AV-S (built as `compare` builds them), and as a second base KD-CASM's, are
// merged with the PVSs of evaluation set 1 itself, which is the evaluator's own objective on
// that set: greedily from the tree's cuts at every halving of its leaves, each cut (and the
// tree's own) then refined (single leaves moved between neighbouring blocks while set 1's cost
// drops, refine_blocks). Scored on set 1 this fits the evaluator's samples (no method that is
// given only construction samples can see them), so it rates the cells better than any honest
// method could expect; set 2 (independent) says what those cells are worth. If even set 1
// cannot bring the cells to the goal's ratio, no merge of these leaves that greedy merging and
// refinement can find reaches it there.
// Prints, per cell count: KD-CASM, AV-S and the oracle cells set 1 rates best, on both sets.
// Usage: viewcells_merge_oracle SCENE SAMPLES CELLS EVAL_SAMPLES COUNT[,COUNT...] [VIEW_BOX|-] [SET2_SAMPLES]
// (VIEW_BOX: xmin,ymin,zmin,xmax,ymax,zmax, as `compare --view-box`; set 2 draws EVAL_SAMPLES
// unless SET2_SAMPLES is given, so that the cells can be fitted on fewer samples than score them.)
// (construction seed 1, evaluation sets seeds 1000004 and 1000005, as scripts/results.sh.)
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <cstdlib>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "viewcells/scene/cost_model.h"
#include "viewcells/core/error.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/eval/evaluate.h"
#include "viewcells/io/scene_io.h"
#include "viewcells/merge/merge.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/sampling/sampler.h"
#include "viewcells/q3/bsp_file.h"

using namespace viewcells;

namespace {

/// Per partition cell (leaf order), the label of its cell in `h`'s cut with `cells` cells.
std::vector<int32_t> cut_labels(const MergeHistory& h, size_t cells) {
  std::vector<int32_t> label(h.leaf_count);
  for (int32_t n : h.cut_after(h.leaf_count - cells))
    for (uint32_t leaf : h.leaves_under(n)) label[leaf] = n;
  return label;
}

/// c(S) of the blocks (`block` per partition cell) with the partition's PVSs.
double blocks_cost(const CellPartition& p, const std::vector<double>& r, const std::vector<int32_t>& block) {
  std::map<int32_t, std::vector<uint32_t>> members;
  for (size_t i = 0; i < block.size(); ++i) members[block[i]].push_back(static_cast<uint32_t>(i));
  double total = 0, weight = 0;
  std::vector<char> seen(r.size(), 0);
  for (const auto& [b, cells] : members) {
    double w = 0, cost = 0;
    std::vector<uint32_t> objects;
    for (uint32_t c : cells) {
      w += p.weight[c];
      for (uint32_t o : p.pvs[c])
        if (!seen[o]) {
          seen[o] = 1;
          cost += r[o];
          objects.push_back(o);
        }
    }
    for (uint32_t o : objects) seen[o] = 0;
    total += w * cost;
    weight += w;
  }
  return total / weight;
}

/// A whole number from the command line (Error naming it if it is not one).
uint64_t whole(const std::string& text, const char* what) {
  size_t used = 0;
  uint64_t v = 0;
  try {
    // stoull takes "-5" and wraps it: only digits are a whole number here.
    if (!text.empty() && std::isdigit(static_cast<unsigned char>(text[0]))) v = std::stoull(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) throw Error(std::string(what) + ": not a whole number: '" + text + "'");
  return v;
}

size_t block_count(const std::vector<int32_t>& block) {
  std::vector<int32_t> b = block;
  std::sort(b.begin(), b.end());
  return static_cast<size_t>(std::unique(b.begin(), b.end()) - b.begin());
}

}  // namespace

int main(int argc, char** argv) {
  viewcells::register_q3_map_format();
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s SCENE SAMPLES CELLS EVAL_SAMPLES COUNT[,COUNT...] [VIEW_BOX|-] [SET2_SAMPLES]\n",
                 argv[0]);
    return 2;
  }
  try {
    const Scene scene = load_scene(argv[1]);
    const auto caster = make_embree_caster(scene);
    // As `compare --samples SAMPLES --seed 1 --max-cells CELLS` builds AV-S and KD-CASM.
    SamplerConfig construction;
    construction.samples = whole(argv[2], "SAMPLES");
    construction.seed = 1;
    construction.show_progress = false;
    if (argc > 6 && std::string(argv[6]) != "-") {
      std::vector<double> v;
      std::stringstream ss(argv[6]);
      for (std::string item; std::getline(ss, item, ',');) {
        size_t used = 0;
        try {
          v.push_back(std::stod(item, &used));
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != item.size()) throw Error("VIEW_BOX: not a number: '" + item + "'");
      }
      if (v.size() != 6) throw Error("the view box needs six numbers: xmin,ymin,zmin,xmax,ymax,zmax");
      construction.view_box = Box3{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
    }
    std::vector<uint32_t> counts;
    {
      std::stringstream ss(argv[5]);
      for (std::string item; std::getline(ss, item, ',');)
        counts.push_back(static_cast<uint32_t>(std::min<uint64_t>(whole(item, "COUNT"), UINT32_MAX)));
    }
    if (counts.empty()) throw Error("no cell counts given");
    const CostModel model;
    const SamplingResult built = sample_segments(scene, *caster, construction);
    auto build = [&](SplitStrategy strategy) {
      SubdivisionConfig sc;
      sc.max_cells = static_cast<uint32_t>(std::min<uint64_t>(whole(argv[3], "CELLS"), 10'000'000));
      sc.strategy = strategy;
      sc.seed = construction.seed;
      sc.show_progress = false;
      return subdivide(scene, built.segments, model, sc);
    };
    const Subdivision s = build(SplitStrategy::kCost);
    const Subdivision kd = build(parse_split_strategy("kd-casm"));
    const std::vector<double> r = per_object_costs(scene, model);

    // Each evaluation set's PVSs of both trees' leaves, drawn as compare draws them (seeds
    // 1000004 and 1000005, a million samples at a time).
    auto draw = [&](uint64_t seed, uint64_t samples) {
      SamplerConfig e = construction;
      e.target_segments = 0;
      e.samples = samples;
      e.seed = seed;
      EvaluationPvs of_s(s, scene.objects.size()), of_kd(kd, scene.objects.size());
      sample_in_chunks(scene, *caster, e, 1'000'000, [&](const SegmentSet& segments, uint64_t) {
        const std::vector<size_t> order = coherent_order(segments, segments.view_box);
        of_s.add(segments, order);
        of_kd.add(segments, order);
      });
      return std::pair{partition_from_subdivision(s, of_s.take()), partition_from_subdivision(kd, of_kd.take())};
    };
    const uint64_t set1 = whole(argv[4], "EVAL_SAMPLES");
    const auto [p1, kd1_cells] = draw(1000004, set1);
    const auto [p2, kd2_cells] = draw(1000005, argc > 7 ? whole(argv[7], "SET2_SAMPLES") : set1);
    const size_t leaves = p1.size();
    for (uint32_t k : counts)
      if (k < 2 || k > leaves)
        throw Error("cell count " + std::to_string(k) + " is not between 2 and the " + std::to_string(leaves) +
                    " leaves built");

    // The candidates, from each tree's leaves (AV-S's, and KD-CASM's as a second base): greedy
    // merging on set 1 from the tree's cut at every halving of its leaves.
    struct Base {
      std::string name;
      const Subdivision* tree;
      const CellPartition *fit, *score;
      std::vector<std::pair<std::string, MergeHistory>> histories;
      std::vector<int32_t> unit;  // single leaves
    };
    std::vector<Base> bases = {{"AV-S", &s, &p1, &p2, {}, {}}, {"KD-CASM", &kd, &kd1_cells, &kd2_cells, {}, {}}};
    for (Base& b : bases) {
      const size_t n = b.fit->size();
      for (size_t from = n; from >= 32; from /= 2) {
        MergeConfig mc;
        mc.show_progress = false;
        mc.min_cells = std::max<uint32_t>(1, *std::min_element(counts.begin(), counts.end()) / 2);
        if (from < n) mc.prefix = subdivision_prefix(*b.tree, from);
        b.histories.emplace_back("greedy from " + std::to_string(from), merge_cells(scene, *b.fit, model, mc));
      }
      b.unit.resize(n);
      std::iota(b.unit.begin(), b.unit.end(), 0);
    }
    std::printf("scene %s, %zu AV-S leaves; costs on evaluation set 1 (fitted) and set 2 (independent)\n", argv[1],
                leaves);
    std::printf("| cells | KD-CASM set 1 | set 2 | AV-S set 1 | set 2 | oracle set 1 | set 2 | oracle / KD-CASM set 1 | set 2 | best oracle |\n");
    std::printf("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n");
    for (uint32_t k : counts) {
      const std::vector<int32_t> avs_blocks = subdivision_blocks(s, k);
      const double avs1 = blocks_cost(p1, r, avs_blocks), avs2 = blocks_cost(p2, r, avs_blocks);
      double best1 = avs1, best2 = avs2;
      std::string best_name = "AV-S's cut";
      for (const Base& b : bases) {
        auto consider = [&](const std::string& name, const std::vector<int32_t>& block) {
          if (block_count(block) != k) return;
          const double c1 = blocks_cost(*b.fit, r, block);
          if (c1 < best1) {
            best1 = c1;
            best2 = blocks_cost(*b.score, r, block);
            best_name = b.name + " leaves, " + name;
          }
        };
        const std::vector<int32_t> cut = subdivision_blocks(*b.tree, k);
        consider("its cut", cut);
        consider("its cut, refined", refine_blocks(scene, *b.fit, model, b.unit, cut, 100));
        for (const auto& [name, h] : b.histories) {
          if (k < h.min_cells() || k > h.leaf_count) continue;
          const std::vector<int32_t> block = cut_labels(h, k);
          consider(name, block);
          consider(name + ", refined", refine_blocks(scene, *b.fit, model, b.unit, block, 100));
        }
      }
      const double kd1 = blocks_cost(kd1_cells, r, subdivision_blocks(kd, k));
      const double kd2 = blocks_cost(kd2_cells, r, subdivision_blocks(kd, k));
      std::printf("| %u | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.3f | %.3f | %s |\n", k, kd1, kd2, avs1, avs2, best1,
                  best2, best1 / kd1, best2 / kd2, best_name.c_str());
      std::fflush(stdout);
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "merge_oracle: %s\n", e.what());
    return 1;
  }
  return 0;
}
