// AGVS paper 4.1: one batch of global visibility sampling: draw the samples, cast them, and
// apply their segments to the PVSs of every cell they pierce, in sample order. The batch is
// the unit of determinism: its samples come from its own random stream, parallel work is cut
// into fixed chunks, and everything that depends on order is applied serially.
// The samples are drawn in batch_draw.cpp and cast in batch_cast.cpp; here they are applied.
#include "batch.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <chrono>
#include <span>
#include <tuple>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/ranks.h"

namespace viewcells {

namespace {

/// Several ranks: an all-to-all of one array per rank, out[q] to rank q (this rank's own is not
/// sent); `take(reader, array)` gets what each other rank sent, in rank order.
template <class T, class Take>
void exchange_arrays(const std::vector<std::vector<T>>& out, const char* what, Take&& take) {
  const size_t me = static_cast<size_t>(ranks::rank());
  std::vector<std::string> to(out.size());
  for (size_t q = 0; q < out.size(); ++q) {
    if (q == me) continue;
    ByteWriter w;
    w.put_array(out[q]);
    to[q] = w.take();
  }
  const std::vector<std::string> from = ranks::exchange(std::move(to));
  std::vector<T> got;
  for (size_t q = 0; q < from.size(); ++q) {
    if (q == me) continue;
    ByteReader r(from[q], what);
    r.get_array(got, from[q].size());
    take(r, got);
  }
}

}  // namespace

struct AgvsSolver::Impl::BatchCounts {
  uint64_t contribution[kDists] = {}, rays[kDists] = {};
  /// The estimator's camera rays over the view space-direction samples, and those that were
  /// wrong pixels (an entry new to the point's cell).
  uint64_t vsd_rays = 0, vsd_wrong = 0;
};

void AgvsSolver::Impl::insert_segments(const std::vector<BatchChunk>& chunks, std::vector<uint32_t>& gains,
                                       std::vector<uint8_t>& flags) {
  // This rank's cells divided among parts, each inserting into its own cells in sample order
  // (so the table, the gains and the flags do not depend on the number of parts): first the
  // (segment, cell) pairs of each part, per chunk, with what inserting needs of the segment,
  // then each part's in order, the outcome kept with each pair; then, per chunk, every pair's
  // outcome added to its segment's. A rank walks only the pairs of its own cells (the casting
  // rank sorted them by rank, or routed them to it).
  struct Pair {
    uint32_t segment;  ///< in the batch
    int32_t cell;
    uint32_t objects[2];
    int32_t camera_cell;
    uint32_t gain = 0;
    uint8_t flags = 0;
  };
  const uint64_t ranks = static_cast<uint64_t>(ranks::size());
  const size_t parts = static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  const size_t n_chunks = chunks.size();
  std::vector<std::vector<std::vector<Pair>>> pairs(n_chunks, std::vector<std::vector<Pair>>(parts));
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    auto add = [&](uint32_t i, int32_t cell, uint32_t a, uint32_t b, int32_t camera) {
      pairs[ci][(static_cast<uint64_t>(cell) / ranks) % parts].push_back(
          {static_cast<uint32_t>(c.seg_start + i), cell, {a, b}, camera});
    };
    for (const BatchChunk::CellPair& p : c.pairs)  // this rank's cells only
      add(p.segment, p.cell, c.segs.object_a[p.segment], c.segs.object_b[p.segment],
          c.camera_cell.empty() ? BatchChunk::kNotCamera : c.camera_cell[p.segment]);
    for (const BatchChunk::RoutedPair& p : c.routed) add(p.segment, p.cell, p.objects[0], p.objects[1], p.camera_cell);
  });
  std::vector<uint64_t> part_entries(parts, 0);
  tbb::parallel_for(size_t{0}, parts, [&](size_t p) {
    for (size_t ci = 0; ci < n_chunks; ++ci)
      for (Pair& pair : pairs[ci][p]) {
        const uint32_t cell = static_cast<uint32_t>(pair.cell);
        const bool origin = pair.camera_cell != BatchChunk::kNotCamera && pair.cell == pair.camera_cell;
        bool contributed[2] = {false, false}, at_origin[2] = {false, false};
        pair.gain = contribute_in_cell([&](uint32_t o) { return pvs.insert_in_row(cell, o); }, pair.objects, origin,
                                       contributed, at_origin);
        pair.flags = static_cast<uint8_t>(contributed[0] | contributed[1] << 1 | at_origin[0] << 2 | at_origin[1] << 3);
        part_entries[p] += pair.gain;
        if (config.filter_statistics) count_hits(pair.cell, pair.objects[0], pair.objects[1]);
      }
  });
  for (uint64_t n : part_entries) pvs.add_entries(n);
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    for (const std::vector<Pair>& of_part : pairs[ci])
      for (const Pair& pair : of_part) {
        gains[pair.segment] += pair.gain;
        flags[pair.segment] |= pair.flags;
      }
  });
}

void AgvsSolver::Impl::return_outcomes(const std::vector<BatchChunk>& chunks, std::vector<uint32_t>& gains,
                                       std::vector<uint8_t>& flags) {
  // Several ranks, routed: each rank sends every segment's outcome in its cells (entries added,
  // flags) back to the segment's caster, which sums and ors them (an all-to-all of the
  // segments that touched anything new).
  const size_t ranks = static_cast<size_t>(ranks::size());
  struct Outcome {
    uint32_t segment;  ///< in the batch
    uint32_t gain;
    uint8_t flags;
  };
  std::vector<std::vector<Outcome>> out(ranks);
  for (size_t k = 0; k < chunks.size(); ++k) {
    const BatchChunk& c = chunks[k];
    if (c.here) continue;
    std::vector<Outcome>& to = out[static_cast<size_t>(chunk_owner(chunks, k))];
    for (uint32_t i = 0; i < c.segment_count; ++i) {
      const size_t at = c.seg_start + i;
      if (gains[at] || flags[at]) to.push_back({static_cast<uint32_t>(at), gains[at], flags[at]});
    }
  }
  exchange_arrays(out, "a rank's segment outcomes", [&](ByteReader& r, const std::vector<Outcome>& got) {
    for (const Outcome& o : got) {
      if (o.segment >= gains.size() || o.gain > 2 * cells.cell_count() || o.flags > 15)
        r.fail("a segment's outcome is out of range");
      gains[o.segment] += o.gain;
      flags[o.segment] |= o.flags;
    }
  });
}

void AgvsSolver::Impl::apply_segments(const BatchSamples& s, const std::vector<BatchChunk>& chunks,
                                      BatchCounts& counts) {
  // Pass 1, in sample order: the table. On several ranks each inserts into its own cells (c
  // mod ranks == rank); then each segment's gains are summed and its flags or-ed over the
  // ranks, at its caster (routed) or on every rank (REF). In one process every cell is this
  // one's and nothing is exchanged. Which samples are the estimator's cameras (their camera
  // segments, found where they were cast) does not depend on the table.
  size_t total = 0;
  for (const BatchChunk& c : chunks) total += c.segment_count;
  std::vector<uint32_t> gains(total, 0);
  std::vector<uint8_t> flags(total, 0);  // contributed a, b; at origin a, b (REF: wrong ray)
  const bool ref = config.method == AgvsMethod::kRef;
  const bool routed = ranks::size() > 1 && !ref;
  // REF: whether the sample's point lies on this segment: its own segment.
  auto on_segment = [&](const BatchChunk& c, size_t i, uint32_t sample) {
    const Vec3 a = c.segs.a(i), ab = c.segs.b(i) - a;
    const double t = dot(s.points[sample] - a, ab);
    return t >= 0 && t <= dot(ab, ab);
  };
  if (ref) {
    std::vector<uint8_t> camera(s.count, 0);
    for (const BatchChunk& c : chunks) {
      for (size_t i = 0; i < c.segs.size(); ++i) {
        // Per cell: the object hit forward from the sample's point, for its cell only; one
        // camera ray, counted once per sample.
        const size_t k = c.seg_start + i;
        const uint32_t sample = c.first + c.sample_of[i];
        if (camera[sample] != 0 || !on_segment(c, i, sample)) continue;
        camera[sample] = 1;
        const int32_t cell = s.ref_cell[sample];
        if (!ranks::mine(static_cast<uint64_t>(cell))) continue;
        const uint32_t object = c.segs.object_b[i];
        if (config.filter_statistics) count_hits(cell, object, kNoObject);
        if (object != kNoObject && pvs.insert(static_cast<uint32_t>(cell), object)) gains[k] = 1, flags[k] = 4;
      }
    }
  } else {
    insert_segments(chunks, gains, flags);
  }
  if (routed) {
    return_outcomes(chunks, gains, flags);
  } else {
    ranks::sum(gains);
    ranks::bit_or(flags);
  }
  // Pass 2: what follows from the segments besides the table, at their caster. Per chunk in
  // parallel (a chunk holds its samples' every segment): the counts, the estimator's camera
  // rays, and the radii at the ends of contributing segments (point location where an end has
  // no object); then, in sample order, the mutation candidates.
  const bool mutations = config.method == AgvsMethod::kAgvs;
  std::vector<uint64_t> chunk_contribution(chunks.size(), 0), chunk_rays(chunks.size(), 0),
      chunk_wrong(chunks.size(), 0);
  std::vector<std::array<double, 2>> radius(mutations ? total : 0);
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    if (!c.here) return;
    std::vector<uint8_t> has_segment(c.size, 0), camera_rays(c.size, 0), wrong_rays(c.size, 0);
    for (size_t i = 0; i < c.segs.size(); ++i) {
      const size_t k = c.seg_start + i;
      const uint32_t local = c.sample_of[i], sample = c.first + local;
      if (!ref && c.segs.object_a[i] == c.segs.object_b[i] && c.segs.object_a[i] != kNoObject)
        flags[k] = static_cast<uint8_t>((flags[k] & ~8u) | ((flags[k] & 4u) << 1));  // both rays were wrong pixels
      has_segment[local] = 1;
      chunk_contribution[ci] += gains[k];
      if (ref) {
        if (camera_rays[local] == 0 && on_segment(c, i, sample)) {
          camera_rays[local] = 1;
          if (flags[k] & 4) wrong_rays[local] = 1;
        }
        continue;
      }
      // The estimator's rays: a camera at the point sees along both rays of its segment.
      if (!c.camera_cell.empty() && c.camera_cell[i] != BatchChunk::kNotCamera) {
        camera_rays[local] = 2;
        wrong_rays[local] = static_cast<uint8_t>(((flags[k] >> 2) & 1) + ((flags[k] >> 3) & 1));
      }
      if (mutations && gains[k] > 0 && (routed || my_lane(sample % lanes.size())))  // its lane's owner feeds it
        radius[k] = {end_radius(c.segs.object_a[i], c.segs.a(i)), end_radius(c.segs.object_b[i], c.segs.b(i))};
    }
    if (c.dist != kVsd) return;
    // The estimator counts view space-direction samples (all of them for SGVS and REF). No
    // segment at all: both rays left the scene without a hit (the caster emits nothing then),
    // so the point is free and its camera sees nothing there: right pixels.
    for (uint32_t k = 0; k < c.size; ++k) {
      chunk_rays[ci] += has_segment[k] ? camera_rays[k] : (ref ? 1 : 2);
      chunk_wrong[ci] += wrong_rays[k];
    }
  });
  for (size_t ci = 0; ci < chunks.size(); ++ci) {
    counts.rays[chunks[ci].dist] += chunks[ci].rays;
    counts.contribution[chunks[ci].dist] += chunk_contribution[ci];
    counts.vsd_rays += chunk_rays[ci];
    counts.vsd_wrong += chunk_wrong[ci];
  }
  if (routed) {
    std::vector<uint64_t> sums(counts.contribution, counts.contribution + kDists);
    sums.push_back(counts.vsd_rays);
    sums.push_back(counts.vsd_wrong);
    ranks::sum(sums);
    std::copy(sums.begin(), sums.begin() + kDists, counts.contribution);
    counts.vsd_rays = sums[kDists], counts.vsd_wrong = sums[kDists + 1];
  }
  if (mutations) {
    if (routed)
      route_candidates(chunks, flags, radius);
    else
      add_candidates(chunks, gains, flags, radius);
  }
  if (ranks::size() == 1) return;
  // The table's size over all ranks' rows (for the mean PVS of the curve and the status).
  partitioned = true;
  std::vector<uint64_t> grown{pvs.entries() - synced_entries};
  ranks::sum(grown);
  global_entries = synced_entries + grown[0];
}

void AgvsSolver::Impl::route_candidates(const std::vector<BatchChunk>& chunks, const std::vector<uint8_t>& flags,
                                        const std::vector<std::array<double, 2>>& radius) {
  // Several ranks, routed: a caster sends each contributing end's candidate to the owner of its
  // sample's lane (index in the batch modulo the lanes); every rank learns each lane's count
  // (a sum); each owner feeds its lanes in sample order (chunk, segment, end), in parallel.
  const auto clock_start = std::chrono::steady_clock::now();
  const int me = ranks::rank();
  const size_t ranks = static_cast<size_t>(ranks::size()), n_lanes = lanes.size();
  struct Routed {
    uint32_t chunk, segment, end, lane;
    Candidate candidate;
  };
  std::vector<std::vector<Routed>> out(ranks);
  std::vector<uint64_t> added(n_lanes, 0);
  for (size_t ci = 0; ci < chunks.size(); ++ci) {
    const BatchChunk& c = chunks[ci];
    if (!c.here) continue;
    for (size_t i = 0; i < c.segs.size(); ++i) {
      const size_t k = c.seg_start + i;
      if (!(flags[k] & 3)) continue;
      const uint32_t l = static_cast<uint32_t>((c.first + c.sample_of[i]) % n_lanes);
      const Vec3 ends[2] = {c.segs.a(i), c.segs.b(i)};
      const uint32_t objs[2] = {c.segs.object_a[i], c.segs.object_b[i]};
      for (uint32_t e = 0; e < 2; ++e) {
        if (!((flags[k] >> e) & 1)) continue;
        ++added[l];
        out[static_cast<size_t>(lane_owner(l))].push_back(
            {static_cast<uint32_t>(ci), static_cast<uint32_t>(i), e, l,
             Candidate{ends[1 - e], ends[e], radius[k][1 - e], radius[k][e], objs[e]}});
      }
    }
  }
  std::vector<Routed> mine = out[static_cast<size_t>(me)];
  const uint32_t n_objects = pvs.object_count();
  exchange_arrays(out, "a rank's mutation candidates", [&](ByteReader& r, const std::vector<Routed>& got) {
    for (const Routed& x : got)
      if (x.lane >= n_lanes || !my_lane(x.lane) || x.chunk >= chunks.size() || x.end > 1 ||
          (x.candidate.object != kNoObject && x.candidate.object >= n_objects))
        r.fail("a routed mutation candidate is out of range");
    mine.insert(mine.end(), got.begin(), got.end());
  });
  std::sort(mine.begin(), mine.end(), [](const Routed& a, const Routed& b) {
    return std::tie(a.chunk, a.segment, a.end) < std::tie(b.chunk, b.segment, b.end);
  });
  std::vector<std::vector<uint32_t>> of_lane(n_lanes);
  for (uint32_t j = 0; j < mine.size(); ++j) of_lane[mine[j].lane].push_back(j);
  ranks::sum(added);
  tbb::parallel_for(size_t{0}, n_lanes, [&](size_t l) {
    MutationLane& lane = lanes[l];
    for (uint32_t j : of_lane[l]) {
      lane.two_point.add(mine[j].candidate, lane_capacity);
      lane.silhouette.add(mine[j].candidate, lane_capacity);
    }
    lane.count = std::min<uint64_t>(lane_capacity, lane.count + added[l]);
  });
  stats.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
}

void AgvsSolver::Impl::add_candidates(const std::vector<BatchChunk>& chunks, const std::vector<uint32_t>& gains,
                                      const std::vector<uint8_t>& flags,
                                      const std::vector<std::array<double, 2>>& radius) {
  // A mutation candidate per end whose object contributed, into the lane of its sample (index
  // in the batch modulo the lanes). The contributing segments are sorted by lane (a counting
  // sort: per chunk and lane, then by offsets), keeping sample order within each lane; then
  // each lane takes its own in parallel. Every rank counts every lane's candidates.
  const auto clock_start = std::chrono::steady_clock::now();
  const size_t n_lanes = lanes.size(), n_chunks = chunks.size();
  auto lane_of = [&](const BatchChunk& c, size_t i) { return (c.first + c.sample_of[i]) % n_lanes; };
  std::vector<uint32_t> per(n_lanes * n_chunks, 0);  // [lane][chunk]: contributing segments
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    for (size_t i = 0; i < c.segs.size(); ++i)
      if (flags[c.seg_start + i] & 3) ++per[lane_of(c, i) * n_chunks + ci];
  });
  std::vector<size_t> start(n_lanes + 1, 0);
  size_t placed = 0;
  for (size_t l = 0; l < n_lanes; ++l) {
    start[l] = placed;
    for (size_t ci = 0; ci < n_chunks; ++ci) {
      const uint32_t n = per[l * n_chunks + ci];
      per[l * n_chunks + ci] = static_cast<uint32_t>(placed);  // now: where the chunk's go
      placed += n;
    }
  }
  start[n_lanes] = placed;
  // The contributing segments, by lane, in sample order: (chunk, segment in the chunk).
  std::vector<std::pair<uint32_t, uint32_t>> order(placed);
  tbb::parallel_for(size_t{0}, n_chunks, [&](size_t ci) {
    const BatchChunk& c = chunks[ci];
    for (size_t i = 0; i < c.segs.size(); ++i)
      if (flags[c.seg_start + i] & 3)
        order[per[lane_of(c, i) * n_chunks + ci]++] = {static_cast<uint32_t>(ci), static_cast<uint32_t>(i)};
  });
  tbb::parallel_for(size_t{0}, n_lanes, [&](size_t l) {
    MutationLane& lane = lanes[l];
    uint64_t added = 0;
    const bool own = my_lane(l);
    for (size_t at = start[l]; at < start[l + 1]; ++at) {
      const BatchChunk& c = chunks[order[at].first];
      const size_t i = order[at].second, k = c.seg_start + i;
      const Vec3 ends[2] = {c.segs.a(i), c.segs.b(i)};
      const uint32_t objs[2] = {c.segs.object_a[i], c.segs.object_b[i]};
      for (int e = 0; e < 2; ++e) {
        if (!((flags[k] >> e) & 1)) continue;
        ++added;
        if (!own) continue;
        const Candidate cand{ends[1 - e], ends[e], radius[k][1 - e], radius[k][e], objs[e]};
        lane.two_point.add(cand, lane_capacity);
        lane.silhouette.add(cand, lane_capacity);
      }
    }
    lane.count = std::min<uint64_t>(lane_capacity, lane.count + added);
  });
  stats.mutation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
}

void AgvsSolver::Impl::sync() {
  if (!partitioned) return;
  // Each row from its owner: the others' copies of it are older subsets (bits) or must not be
  // counted twice (the filter's densities), so they are cleared before the reduction.
  const uint32_t n_cells = pvs.cell_count();
  const size_t words = pvs.words_per_row(), n_objects = pvs.object_count();
  std::vector<uint64_t>& bits = pvs.raw_bits();
  for (uint32_t c = 0; c < n_cells; ++c)
    if (!ranks::mine(c)) std::fill(bits.begin() + c * words, bits.begin() + (c + 1) * words, 0);
  ranks::bit_or(bits);
  pvs.recount();
  if (config.filter_statistics) {
    for (uint32_t c = 0; c < n_cells; ++c)
      if (!ranks::mine(c)) {
        cell_samples[c] = 0;
        std::fill(hit_counts.begin() + c * n_objects, hit_counts.begin() + (c + 1) * n_objects, 0);
      }
    ranks::sum(cell_samples);
    ranks::sum(hit_counts);
  }
  // The mutation lanes, each from its owner.
  std::vector<std::string> items(lanes.size());
  for (size_t l = 0; l < lanes.size(); ++l)
    if (my_lane(l)) {
      ByteWriter w;
      save_lane(w, lanes[l]);
      items[l] = w.take();
    }
  ranks::share(items, [&](size_t l) { return lane_owner(l); });
  for (size_t l = 0; l < lanes.size(); ++l)
    if (!my_lane(l)) {
      ByteReader r(items[l], "a rank's mutation candidates");
      lanes[l] = load_lane(r, items[l].size());
    }
  synced_entries = global_entries = pvs.entries();
  partitioned = false;
}

void AgvsSolver::Impl::batch(uint64_t index, uint32_t n) {
  double share[kDists];
  shares(share);
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto t = Clock::now();
  double lanes_before = stats.mutation_seconds;  // the lanes' time is counted apart
  BatchSamples s;
  draw_samples(index, n, share, s);
  stats.draw_seconds += since(t) - (stats.mutation_seconds - lanes_before);
  t = Clock::now();
  const std::vector<BatchChunk> chunks = cast_samples(s);
  const size_t count = s.count;
  stats.cast_seconds += since(t);
  t = Clock::now();
  lanes_before = stats.mutation_seconds;
  // Apply in sample order (contributions depend on what came before).
  BatchCounts counts;
  counts.rays[kSil] += s.discovery_rays;
  apply_segments(s, chunks, counts);
  for (const BatchChunk& c : chunks) {
    stats.segments += c.segment_count;
    stats.pierced_cells += c.pierced;
  }
  const uint64_t vsd_rays = counts.vsd_rays, vsd_contributing = counts.vsd_wrong;
  uint64_t samples_of[kDists];
  for (int d = 0; d < kDists; ++d) samples_of[d] = s.end_of[d] - s.first_of[d];
  update_weights(share, samples_of, counts.contribution, counts.rays);
  stats.samples += count;
  stats.batches += 1;
  stats.mutation_candidates = mutation_candidates();
  stats.camera_rays += vsd_rays;
  stats.wrong_camera_rays += vsd_contributing;
  update_estimate(vsd_rays, vsd_contributing);
  stats.apply_seconds += since(t) - (stats.mutation_seconds - lanes_before);
}

}  // namespace viewcells
