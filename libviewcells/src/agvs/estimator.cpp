// AGVS paper 4.5: termination by the pixel error: the estimate from the view space-direction
// rays (equation 5) and its bound (eval/frames.h measures it with rendered cameras).
#include "solver_impl.h"

namespace viewcells {

void AgvsSolver::Impl::update_estimate(uint64_t rays, uint64_t wrong) {
  window.emplace_front(rays, wrong);
  window_total += rays;
  evaluate_window();
}

void AgvsSolver::Impl::evaluate_window() {
  const uint64_t reach = std::max<uint64_t>(window_total / 2, 1);
  uint64_t n = 0, nc = 0;
  size_t used = 0;
  error = error_bound = std::numeric_limits<double>::quiet_NaN();
  stats.window_rays = 0;
  for (const auto& [r, c] : window) {
    if (used > 0 && n + r > reach) break;
    n += r;
    nc += c;
    ++used;
    if (nc == 0) continue;  // e = 0 would need an infinite window
    const double e = static_cast<double>(nc) / static_cast<double>(n);
    const double need = (1 - e) / (config.window_k * config.window_k * e * (1 - config.window_p));
    if (static_cast<double>(n) >= need) {
      error = config.resolution * e;
      stats.window_rays = n;
      break;
    }
  }
  if (std::isnan(error) && n > 0) {
    // Wilson-Hilferty: the 90% upper bound of a Poisson mean with nc events.
    const double k1 = static_cast<double>(nc) + 1, z = 1.2816;
    const double upper = k1 * std::pow(1 - 1 / (9 * k1) + z / (3 * std::sqrt(k1)), 3);
    error_bound = config.resolution * upper / static_cast<double>(n);
    stats.window_rays = n;
  }
  // Batches beyond the newer half never come back into reach: a new batch moves every older
  // one further back by all its rays, the half's start by only half of them.
  size_t keep = 0;
  for (uint64_t acc = 0; keep < window.size() && (keep == 0 || acc + window[keep].first <= reach); ++keep)
    acc += window[keep].first;
  window.resize(keep);
}

}  // namespace viewcells
