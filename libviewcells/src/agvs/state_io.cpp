// Saving and resuming the solver (not in the paper): the whole state, so that a resumed run
// continues exactly as an uninterrupted one.
#include "solver_impl.h"

namespace viewcells {

namespace {
constexpr char kStateMagic[5] = "VAGS";
constexpr uint32_t kStateVersion = 5;  // 5: stationary samples drawn by Halton index ranges
}  // namespace

void AgvsSolver::save(const std::string& path, uint64_t identity) const {
  const Impl& m = *impl_;
  ByteWriter w;
  w.put(identity);
  w.put(static_cast<int32_t>(m.config.method));
  w.put(m.config.seed);
  w.put(m.config.batch_size);
  w.put(m.config.min_share);
  w.put(m.config.mutation_lanes);
  m.pvs.save(w);
  const AgvsStats& s = m.stats;
  w.put(s.samples), w.put(s.rays), w.put(s.batches), w.put(s.seconds), w.put(s.window_rays);
  w.put(s.camera_rays), w.put(s.wrong_camera_rays);
  for (int d = 0; d < kDists; ++d) {
    w.put(s.dist_samples[d]), w.put(s.dist_rays[d]), w.put(s.dist_contribution[d]), w.put(s.dist_probability[d]);
    w.put(m.halton_index[d]), w.put(m.weight[d]), w.put(m.recent_contribution[d]), w.put(m.recent_rays[d]);
  }
  w.put(m.last_calibration);
  w.put(static_cast<uint8_t>(m.calibrated));
  w.put(m.error);
  for (const MutationLane& lane : m.lanes) m.save_lane(w, lane);
  w.put(m.window_total);
  w.put<uint64_t>(m.window.size());
  for (const auto& [n, nc] : m.window) w.put(n), w.put(nc);
  w.put<uint64_t>(s.curve.size());
  for (const AgvsPoint& p : s.curve) w.put(p);
  w.put(static_cast<uint8_t>(m.config.filter_statistics));
  if (m.config.filter_statistics) {
    w.put_array(m.cell_samples);
    w.put_array(m.hit_counts);
  }
  write_container(path, kStateMagic, kStateVersion, w.data());
}

Box3 AgvsSolver::Impl::candidate_bounds() const {
  // Candidate ends lie in the view box or on the scene; a little slack for rounding.
  Box3 ends = cells.view_box();
  ends.extend(scene_->bounds.lo);
  ends.extend(scene_->bounds.hi);
  const Vec3 slack = ends.extent() * 1e-6 + Vec3{1e-9, 1e-9, 1e-9};
  ends.lo = ends.lo - slack, ends.hi = ends.hi + slack;
  return ends;
}

MutationLane AgvsSolver::Impl::load_lane(ByteReader& r, size_t payload) const {
  const Box3 ends = candidate_bounds();
  const uint32_t n_objects = pvs.object_count();
  MutationLane lane;
  lane.two_point = CandidateBuffer::load(r, lane_capacity, payload, ends, n_objects);
  lane.silhouette = CandidateBuffer::load(r, lane_capacity, payload, ends, n_objects);
  if (lane.two_point.size() != lane.silhouette.size()) r.fail("the mutations' candidate counts differ");
  lane.count = lane.two_point.size();
  return lane;
}

uint64_t AgvsSolver::state_identity(const std::string& path) {
  uint32_t version = 0;
  const std::string payload = read_container(path, kStateMagic, kStateVersion, version);
  ByteReader r(payload, path);
  return r.get<uint64_t>();
}

void AgvsSolver::load(const std::string& path, uint64_t identity) {
  Impl& m = *impl_;
  uint32_t version = 0;
  const std::string payload = read_container(path, kStateMagic, kStateVersion, version);
  ByteReader r(payload, path);
  if (r.get<uint64_t>() != identity) throw Error(path, 0, "this state belongs to another scene or other view cells");
  const int32_t method = r.get<int32_t>();
  const uint64_t seed = r.get<uint64_t>();
  const uint32_t batch = r.get<uint32_t>();
  const double min_share = r.get<double>();
  const uint32_t lanes = r.get<uint32_t>();
  if (method != static_cast<int32_t>(m.config.method) || seed != m.config.seed || batch != m.config.batch_size ||
      min_share != m.config.min_share || lanes != m.config.mutation_lanes)
    throw Error(path, 0,
                "this state was computed with another method, seed, batch size, minimum share or mutation lanes");
  // Read everything into locals first: a corrupt file leaves the solver as it was.
  GlobalPvs pvs = GlobalPvs::load(r, m.pvs.cell_count(), m.pvs.object_count());
  AgvsStats s = m.stats;
  s.samples = r.get<uint64_t>(), s.rays = r.get<uint64_t>(), s.batches = r.get<uint64_t>();
  s.seconds = r.get<double>(), s.window_rays = r.get<uint64_t>();
  s.camera_rays = r.get<uint64_t>(), s.wrong_camera_rays = r.get<uint64_t>();
  uint64_t halton[kDists];
  double weight[kDists], recent_c[kDists], recent_r[kDists];
  for (int d = 0; d < kDists; ++d) {
    s.dist_samples[d] = r.get<uint64_t>(), s.dist_rays[d] = r.get<uint64_t>();
    s.dist_contribution[d] = r.get<uint64_t>(), s.dist_probability[d] = r.get<double>();
    halton[d] = r.get<uint64_t>(), weight[d] = r.get<double>(), recent_c[d] = r.get<double>(), recent_r[d] = r.get<double>();
  }
  const uint64_t last_calibration = r.get<uint64_t>();
  const bool calibrated = r.get<uint8_t>() != 0;
  const double error = r.get<double>();
  if (!(s.seconds >= 0 && s.seconds < 1e9)) r.fail("the time spent is out of range");
  for (int d = 0; d < kDists; ++d)
    if (!(weight[d] >= 0 && weight[d] < 1e300) || !(recent_c[d] >= 0 && recent_c[d] < 1e300) ||
        !(recent_r[d] >= 0 && recent_r[d] < 1e300) || !(s.dist_probability[d] >= 0 && s.dist_probability[d] <= 1))
      r.fail("mixture weights out of range");
  std::vector<MutationLane> mutation_lanes;
  for (uint32_t l = 0; l < lanes; ++l) mutation_lanes.push_back(m.load_lane(r, payload.size()));
  const uint64_t window_total = r.get<uint64_t>();
  const uint64_t windows = r.get<uint64_t>();
  if (windows > payload.size()) r.fail("estimator window too long");
  std::deque<std::pair<uint64_t, uint64_t>> window;
  for (uint64_t k = 0; k < windows; ++k) {
    const uint64_t n = r.get<uint64_t>(), nc = r.get<uint64_t>();
    window.emplace_back(n, nc);
  }
  const uint64_t points = r.get<uint64_t>();
  if (points > payload.size()) r.fail("curve too long");
  s.curve.clear();
  for (uint64_t k = 0; k < points; ++k) s.curve.push_back(r.get<AgvsPoint>());
  const bool with_filter = r.get<uint8_t>() != 0;
  if (with_filter != m.config.filter_statistics)
    throw Error(path, 0, with_filter ? "this state keeps the visibility filter's statistics: resume with the filter"
                                     : "this state has no visibility filter statistics: resume without the filter");
  std::vector<uint64_t> cell_samples;
  std::vector<uint16_t> hit_counts;
  std::vector<GlobalPvs> references;  ///< for the curve's coverage only
  if (with_filter) {
    r.get_array(cell_samples, m.cell_samples.size());
    r.get_array(hit_counts, m.hit_counts.size());
    if (cell_samples.size() != m.cell_samples.size() || hit_counts.size() != m.hit_counts.size())
      r.fail("filter statistics of the wrong size");
  }
  if (!r.at_end()) r.fail("trailing bytes");
  // Commit.
  m.pvs = std::move(pvs);
  m.stats = std::move(s);
  for (int d = 0; d < kDists; ++d)
    m.halton_index[d] = halton[d], m.weight[d] = weight[d], m.recent_contribution[d] = recent_c[d],
    m.recent_rays[d] = recent_r[d];
  m.last_calibration = last_calibration;
  m.calibrated = calibrated;
  m.error = error;
  m.lanes = std::move(mutation_lanes);
  m.stats.mutation_candidates = m.mutation_candidates();
  m.window = std::move(window);
  m.window_total = window_total;
  m.cell_samples = std::move(cell_samples);
  m.hit_counts = std::move(hit_counts);
  m.evaluate_window();
}

}  // namespace viewcells
