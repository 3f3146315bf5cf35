#pragma once
// Inside merge_validated (validated/merge.h): which pieces of the candidate histories it
// takes, and how it walks the held-out samples. Private to the library (the tests see it).
#include <cstdint>
#include <vector>

#include "viewcells/validated/merge.h"

namespace viewcells {

/// Whether merge_validated takes a piece of a candidate history (counts scored in it, the sum
/// of their held-out log(cost / AV-S's cost) and the largest): its worst count is at most
/// `worst_allowed` above AV-S's, and at most its mean gain over the piece's counts. A piece
/// that gains less on average than it loses at one count is a tie within the held-out
/// samples' noise, and a tie keeps AV-S's own order (merging must not make a cut worse).
bool merge_piece_allowed(double sum, double worst, size_t counts, double worst_allowed);

/// merge_validated's test of a piece under `allowed`: `worst` is the largest log ratio of its
/// counts from allowed.low_below up, `worst_low` of those below (each at least 0). A greedy
/// piece is held at every count to allowed.greedy; a refined one to allowed.refined from
/// low_below up and to allowed.refined_low below. Both pass merge_piece_allowed with the worst
/// that is held to the goals' counts (every count for a greedy piece).
bool merge_piece_within(const PieceAllowance& allowed, bool refined, double sum, double worst, double worst_low,
                        size_t counts);

/// A candidate history's held-out scores at the counts scored (0 where it or AV-S does not
/// reach the count).
struct CandidateScores {
  std::vector<double> log_ratio;  ///< mean over the held-out sets of log(cost / AV-S's cost)
  std::vector<double> worst;      ///< the largest of them
  std::vector<uint8_t> scored;    ///< 1 where the history and AV-S both reach the count
  bool barrier_cut = false;       ///< its cut at its barrier is AV-S's (the barrier held)
};

/// A piece of the chosen history: `candidate`'s merges (-1: AV-S's own order) from AV-S's cut
/// at `from` cells down to `to` (its barrier; 0: the end).
struct ChosenPiece {
  int candidate = -1;
  uint32_t from = 0, to = 0;
};

/// merge_validated's choice, from the leaves down: per range of counts the lowest sum of log
/// ratios over the counts scored. Each candidate is taken whole, or down to its barrier (where
/// its cut is AV-S's) and then the best choice below; the split is preferred when it does at
/// least as well, so that merges the held-out samples cannot tell from AV-S's order give way
/// to it. Every piece passes merge_piece_within. An option must beat the best so far by more
/// than rounding: ties keep the earlier, AV-S's own order first. `counts` ascending. A count's
/// worst is raised by `spread_margin` times its distance from the count's mean
/// (ValidatedMergeConfig::spread_margin) before a piece's worst is taken.
std::vector<ChosenPiece> choose_merge_pieces(const std::vector<MergeStart>& candidates,
                                             const std::vector<CandidateScores>& scores,
                                             const std::vector<size_t>& counts, uint32_t leaves,
                                             const PieceAllowance& allowed, double spread_margin);

/// The held-out random samples are drawn and walked down the tree this many at a time (memory).
constexpr uint64_t kHeldOutChunk = 1'000'000;

}  // namespace viewcells
