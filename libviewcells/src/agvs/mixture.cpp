// AGVS paper 4.2: the adaptive mixture: each distribution's share of the next batch, from its
// recent contribution per ray.
#include "solver_impl.h"

#include <numeric>

namespace viewcells {

void AgvsSolver::Impl::shares(double share[kDists]) {
  std::fill(share, share + kDists, 0.0);
  if (config.method != AgvsMethod::kAgvs) {
    share[kVsd] = 1;
    return;
  }
  const bool candidates = mutation_candidates() > 0;  // both mutations' (the buffers hold the same number)
  auto usable = [&](int d) { return (d != kTpm && d != kSil) || candidates; };
  const bool calibrate = !calibrated || stats.samples - last_calibration >= config.recalibrate_every;
  // A distribution not tried yet (the mutation, before its first candidates) gets the
  // best weight: it is then measured like the others.
  const double best = *std::max_element(weight, weight + kDists);
  double total = 0;
  for (int d = 0; d < kDists; ++d) {
    const double w = recent_rays[d] > 0 ? weight[d] : best;
    share[d] = usable(d) ? (calibrate ? 1.0 : w) : 0.0;
    total += share[d];
  }
  if (!(total > 0)) {  // nothing contributed in the last batch: spread evenly
    for (int d = 0; d < kDists; ++d) share[d] = usable(d) ? 1.0 : 0.0;
    total = std::accumulate(share, share + kDists, 0.0);
  }
  for (int d = 0; d < kDists; ++d) share[d] /= total;
  if (share[kVsd] < config.min_share) {  // keep the estimator's rays coming
    const double rest = 1 - share[kVsd];
    for (int d = 1; d < kDists; ++d) share[d] *= (1 - config.min_share) / rest;
    share[kVsd] = config.min_share;
  }
  if (calibrate) {
    calibrated = true;
    last_calibration = stats.samples;
  }
}

void AgvsSolver::Impl::update_weights(const double share[kDists], const uint64_t samples[kDists],
                                      const uint64_t contribution[kDists], const uint64_t rays[kDists]) {
  // Weights for the next batch: contribution per ray, over the recent batches (each batch
  // counts half as much as the one after it: small contributions are noisy).
  for (int d = 0; d < kDists; ++d) {
    recent_contribution[d] = 0.5 * recent_contribution[d] + static_cast<double>(contribution[d]);
    recent_rays[d] = 0.5 * recent_rays[d] + static_cast<double>(rays[d]);
    weight[d] = recent_rays[d] > 0 ? recent_contribution[d] / recent_rays[d] : 0.0;
    stats.dist_samples[d] += samples[d];
    stats.dist_rays[d] += rays[d];
    stats.dist_contribution[d] += contribution[d];
    stats.dist_probability[d] = share[d];
    stats.rays += rays[d];
  }
}

}  // namespace viewcells
