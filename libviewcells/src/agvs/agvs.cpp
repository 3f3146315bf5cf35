// AGVS paper 4.6: the sampling loop (batches until a termination criterion holds) and the
// solver's public API.
#include "solver_impl.h"

#include <chrono>
#include <cstdio>
#include <optional>

#include "viewcells/core/interrupt.h"
#include "viewcells/core/names.h"
#include "viewcells/core/progress.h"

namespace viewcells {

namespace {
constexpr EnumNames<AgvsMethod, 3> kMethodNames{
    {{{AgvsMethod::kAgvs, "agvs"}, {AgvsMethod::kSgvs, "sgvs"}, {AgvsMethod::kRef, "ref"}}}, "PVS method"};
constexpr EnumNames<AgvsDistribution, 5> kDistributionNames{
    {{{AgvsDistribution::kViewSpaceDirection, "view space-direction"},
      {AgvsDistribution::kObjectDirection, "object-direction"},
      {AgvsDistribution::kTwoPoint, "two-point"},
      {AgvsDistribution::kTwoPointMutation, "two-point mutation"},
      {AgvsDistribution::kSilhouetteMutation, "silhouette mutation"}}},
    "AGVS distribution"};
}  // namespace

AgvsMethod parse_agvs_method(const std::string& name) { return kMethodNames.parse(name); }

const char* to_string(AgvsMethod m) { return kMethodNames.name(m); }

const char* to_string(AgvsDistribution d) { return kDistributionNames.name(d); }

AgvsSolver::AgvsSolver(const Scene& scene, const RayCaster& caster, const CellLocator& cells, const AgvsConfig& config) {
  if (config.batch_size == 0) throw Error("the batch size must be positive");
  if (config.mutation_lanes == 0 || config.mutation_lanes > kMaxMutationLanes ||
      config.mutation_lanes > config.mutation_buffer)
    throw Error("the mutation lanes must be between 1 and " + std::to_string(kMaxMutationLanes) +
                ", and at most the mutation buffer's size");
  if (!(config.min_share >= 0 && config.min_share <= 1)) throw Error("the minimum share must be within [0, 1]");
  if (!(config.window_p > 0 && config.window_p < 1) || !(config.window_k > 0))
    throw Error("the pixel error window needs 0 < P < 1 and k > 0");
  if (scene.object_count() == 0) throw Error("cannot sample an empty scene");
  impl_ = std::make_unique<Impl>(scene, caster, cells, config);
}

AgvsSolver::~AgvsSolver() = default;

void AgvsSolver::set_limits(uint64_t max_samples, double max_seconds, double pixel_error) {
  impl_->config.max_samples = max_samples;
  impl_->config.max_seconds = max_seconds;
  impl_->config.pixel_error = pixel_error;
}

void AgvsSolver::set_checkpoint(double seconds, std::function<void()> save) {
  impl_->checkpoint_every = seconds;
  impl_->checkpoint = std::move(save);
}

void AgvsSolver::run() {
  Impl& m = *impl_;
  const AgvsConfig& c = m.config;
  if (!c.max_samples && !(c.max_seconds > 0) && !(c.pixel_error > 0))
    throw Error("the PVS computation needs a limit: samples, seconds or a pixel error");
  const auto start = std::chrono::steady_clock::now();
  const double before = m.stats.seconds;
  // The limits count from the start of the computation (a resumed state included) and are
  // checked between batches, so that where a run stops never changes the batches: a run
  // resumed from a state continues exactly as an uninterrupted one.
  // The bar follows the samples, else the time; with only a pixel error to reach, a counter.
  // Its status line shows the mean PVS and the pixel error estimate (or bound).
  const bool by_samples = c.max_samples > 0, by_time = !by_samples && c.max_seconds > 0;
  const bool show = c.show_progress && (!by_samples || c.max_samples > m.stats.samples);
  std::optional<Progress> progress;
  const uint64_t start_ms = static_cast<uint64_t>(before * 1000);
  if (show)
    progress.emplace("pvs", by_samples ? c.max_samples - m.stats.samples
                            : by_time  ? static_cast<uint64_t>(std::max(0.0, c.max_seconds - before) * 1000)
                                       : 0);
  uint64_t shown_ms = start_ms;
  auto last_checkpoint = start;
  if (!m.partitioned) m.synced_entries = m.global_entries = m.pvs.entries();
  while (true) {
    throw_if_interrupted("AGVS");
    const double seconds = before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (c.max_samples && m.stats.samples >= c.max_samples) {
      m.stats.stop_reason = "reached " + std::to_string(c.max_samples) + " samples";
      break;
    }
    // Clock decisions are rank 0's on a cluster (ranks::agree), so that all ranks stop together.
    if (c.max_seconds > 0 && ranks::agree(seconds >= c.max_seconds)) {
      m.stats.stop_reason = "reached the time limit";
      break;
    }
    if (c.pixel_error > 0 && !std::isnan(m.error) && m.error <= c.pixel_error) {
      char text[96];
      std::snprintf(text, sizeof text, "estimated pixel error at most %g", c.pixel_error);
      m.stats.stop_reason = text;
      break;
    }
    if (c.pixel_error > 0 && !std::isnan(m.error_bound) && m.error_bound <= c.pixel_error) {
      char text[96];
      std::snprintf(text, sizeof text, "pixel error below %g with probability 0.9", c.pixel_error);
      m.stats.stop_reason = text;
      break;
    }
    const uint64_t done = m.stats.samples;
    m.batch(m.stats.batches, c.batch_size);
    if (show) {
      char status[160];
      if (!std::isnan(m.error))
        std::snprintf(status, sizeof status, "mean PVS %.1f, pixel error ~%.2f", m.mean_pvs(), m.error);
      else if (!std::isnan(m.error_bound))
        std::snprintf(status, sizeof status, "mean PVS %.1f, pixel error < %.2f", m.mean_pvs(), m.error_bound);
      else
        std::snprintf(status, sizeof status, "mean PVS %.1f", m.mean_pvs());
      progress->set_status(status);
      if (by_time) {
        const uint64_t now_ms = static_cast<uint64_t>(
            (before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()) * 1000);
        progress->advance(now_ms - shown_ms);
        shown_ms = now_ms;
      } else {
        progress->advance(m.stats.samples - done);
      }
    }
    m.stats.seconds = before + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    AgvsPoint point{m.stats.seconds, m.stats.samples, m.stats.rays, m.mean_pvs(), m.error, m.error_bound,
                    m.stats.camera_rays, m.stats.wrong_camera_rays};
    if (!m.references.empty()) m.sync();  // coverage needs the whole table
    for (size_t k = 0; k < m.references.size(); ++k) point.covered[k] = m.pvs.common_entries(m.references[k]);
    m.stats.curve.push_back(point);
    if (m.checkpoint && m.checkpoint_every > 0 &&
        ranks::agree(std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint).count() >=
                       m.checkpoint_every)) {
      m.sync();  // the state of every rank's rows
      m.checkpoint();
      last_checkpoint = std::chrono::steady_clock::now();
    }
  }
  if (show) progress->finish();
  m.sync();  // every rank holds the whole table when run() returns
}

void AgvsSolver::add_reference(GlobalPvs reference) {
  if (impl_->references.size() >= AgvsPoint::kReferences)
    throw Error("at most " + std::to_string(AgvsPoint::kReferences) + " reference solutions");
  if (reference.cell_count() != impl_->pvs.cell_count() || reference.object_count() != impl_->pvs.object_count())
    throw Error("the reference PVSs are for other view cells or another scene");
  impl_->references.push_back(std::move(reference));
}

const GlobalPvs& AgvsSolver::pvs() const { return impl_->pvs; }
const AgvsStats& AgvsSolver::stats() const { return impl_->stats; }
double AgvsSolver::pixel_error() const { return impl_->error; }
double AgvsSolver::pixel_error_bound() const { return impl_->error_bound; }
double AgvsSolver::mean_pvs() const { return impl_->mean_pvs(); }

}  // namespace viewcells
