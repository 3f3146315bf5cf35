// AGVS paper 4.1: a batch's samples cast, in fixed chunks of one distribution's samples each,
// into segments and the (segment, cell) pairs they pierce (batch.h).
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

void AgvsSolver::Impl::cast_ref_chunk(const BatchSamples& s, BatchChunk& c) const {
  // The paper's REF: one ray per sample, forward from the point; what it hits first goes into
  // the point's cell. Where closed solids make inside and outside (empty space detection), a
  // back face first means the point is inside a solid: no camera stands there, nothing is seen.
  // See-through surfaces the ray crosses are not followed.
  std::vector<Ray> rays(c.size);
  std::vector<Hit> hits(c.size);
  for (uint32_t k = 0; k < c.size; ++k) rays[k] = Ray{s.points[c.first + k], s.dirs[c.first + k]};
  caster_ref().intersect(rays, hits);
  c.rays = c.size;
  c.segs = SegmentSet{};
  c.segs.reserve(c.size);
  c.sample_of.clear();
  const double far = 2 * cells.view_box().diagonal();
  for (uint32_t k = 0; k < c.size; ++k) {
    const Hit& h = hits[k];
    const bool seen = h.hit() && (h.front || !stats.empty_space.enabled);
    const Vec3 end = rays[k].origin + rays[k].dir * (h.hit() ? h.t : far);
    c.segs.push_back(rays[k].origin, end, kNoObject, seen ? h.object : kNoObject);
    c.sample_of.push_back(k);
  }
}

std::vector<AgvsSolver::Impl::BatchChunk> AgvsSolver::Impl::cast_samples(BatchSamples& s) {
  // Cast in fixed chunks within each distribution, in parallel; outputs in sample order.
  std::vector<BatchChunk> chunks;
  auto add_chunks = [&](int d, uint32_t first, uint32_t end, int32_t lane) {
    for (uint32_t f = first; f < end; f += kChunkSamples) {
      BatchChunk c;
      c.first = f;
      c.size = std::min(kChunkSamples, end - f);
      c.dist = d;
      c.lane = lane;
      chunks.push_back(std::move(c));
    }
  };
  for (int d : kOrder) {
    if (config.method == AgvsMethod::kRef) {
      add_chunks(d, s.first_of[d], s.end_of[d], -1);
    } else if (d == kSil || d == kTpm) {
      // A mutation's samples in runs of one lane group each.
      const BatchSamples::LaneRange* run = nullptr;
      uint32_t end = 0;
      for (const BatchSamples::LaneRange& r : s.lane_ranges) {
        if (r.dist != d) continue;
        if (run && lane_group(r.lane) == lane_group(run->lane)) {
          end = r.first + r.size;
          continue;
        }
        if (run) add_chunks(d, run->first, end, static_cast<int32_t>(run->lane));
        run = &r, end = r.first + r.size;
      }
      if (run) add_chunks(d, run->first, end, static_cast<int32_t>(run->lane));
    } else {
      for (const BatchSamples::HaltonRange& r : s.stationary) {
        if (r.dist != d) continue;
        BatchChunk c;
        c.dist = d;
        c.halton_first = r.first;
        c.halton_count = r.count;
        chunks.push_back(std::move(c));
      }
    }
  }
  // A chunk: its samples (a stationary distribution's drawn here), cast, and the cells of each
  // segment.
  auto cast_chunk = [&](BatchChunk& c) {
    if (config.method == AgvsMethod::kRef) {
      cast_ref_chunk(s, c);
      return;
    }
    std::vector<Vec3> drawn_points, drawn_dirs;
    const Vec3* points = s.points.data() + c.first;
    const Vec3* dirs = s.dirs.data() + c.first;
    if (c.halton_count > 0) {
      drawn_points.reserve(std::min(c.halton_count, 2 * kChunkSamples));
      drawn_dirs.reserve(std::min(c.halton_count, 2 * kChunkSamples));
      draw_stationary(c.dist, c.halton_first, c.halton_count, drawn_points, drawn_dirs);
      c.size = static_cast<uint32_t>(drawn_points.size());
      points = drawn_points.data(), dirs = drawn_dirs.data();
    }
    c.rays = caster().cast(std::span<const Vec3>(points, c.size), std::span<const Vec3>(dirs, c.size), c.segs,
                           c.sample_of);
    if (c.dist == kVsd) {
      // The estimator's camera segment of each sample: its first segment through its point
      // (re-casts of points inside solids start elsewhere; see-through companions are the
      // first one's).
      std::vector<uint8_t> seen(c.size, 0);
      c.camera_cell.assign(c.segs.size(), BatchChunk::kNotCamera);
      for (size_t i = 0; i < c.segs.size(); ++i) {
        const uint32_t k = c.sample_of[i];
        const Vec3 a = c.segs.a(i), ab = c.segs.b(i) - a;
        const double t = dot(points[k] - a, ab);
        if (seen[k] || !(t >= 0 && t <= dot(ab, ab))) continue;
        seen[k] = 1;
        c.camera_cell[i] = cells.cell_at(points[k]);
      }
    }
    std::vector<std::tuple<int32_t, double, double>> stack;
    std::vector<int32_t> pierced;
    for (size_t i = 0; i < c.segs.size(); ++i) {
      cells.cells_of_segment(c.segs.a(i), c.segs.b(i), pierced, stack);
      for (int32_t cell : pierced) c.pairs.push_back({static_cast<uint32_t>(i), cell});
    }
    c.pierced = c.pairs.size();
  };
  if (ranks::size() > 1 && config.method == AgvsMethod::kRef) {
    gather_chunks(chunks, cast_chunk);
  } else if (ranks::size() > 1) {
    route_chunks(chunks, cast_chunk);
  } else {
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) { cast_chunk(chunks[k]); });
  }
  for (BatchChunk& c : chunks)
    if (c.here) c.segment_count = static_cast<uint32_t>(c.segs.size());
  // The stationary distributions' samples follow the mutations' (kOrder), numbered in chunk
  // order now that each chunk's count is known.
  uint32_t next = static_cast<uint32_t>(s.points.size());
  int last = -1;
  for (BatchChunk& c : chunks) {
    if (c.halton_count == 0) continue;
    if (c.dist != last) s.first_of[c.dist] = next, last = c.dist;
    c.first = next;
    next += c.size;
    s.end_of[c.dist] = next;
  }
  s.count = next;
  size_t total = 0;
  for (BatchChunk& c : chunks) {
    c.seg_start = total;
    total += c.segment_count;
  }
  return chunks;
}

/// What applying a batch counted: per distribution, and the estimator's camera rays per sample
/// (0 when the sample's point is inside a solid: no camera stands there) and those that were
/// wrong pixels (an entry new to the point's cell).

void AgvsSolver::Impl::gather_chunks(std::vector<BatchChunk>& chunks, const std::function<void(BatchChunk&)>& cast_chunk) {
  // Several ranks, REF: each casts the chunks it owns, and every rank receives all of them
  // (REF inserts one object a sample, into the sample's cell; every rank's cells are read
  // from the segments).
  std::vector<std::string> items(chunks.size());
  auto owner = [&](size_t k) { return chunk_owner(chunks, k); };
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) {
    if (owner(k) != ranks::rank()) return;
    BatchChunk& c = chunks[k];
    cast_chunk(c);
    ByteWriter w;
    w.put(c.rays);
    w.put_array(c.sample_of);
    put_segments(w, c.segs);
    items[k] = w.take();
  });
  ranks::share(items, owner);
  for (size_t k = 0; k < chunks.size(); ++k) {
    BatchChunk& c = chunks[k];
    ByteReader r(items[k], "a rank's casting results");
    c.rays = r.get<uint64_t>();
    r.get_array(c.sample_of, items[k].size());
    get_segments(r, c.segs, items[k].size());
    if (c.sample_of.size() != c.segs.size()) r.fail("a chunk's segments and samples differ in number");
    for (uint32_t sample : c.sample_of)
      if (sample >= c.size) r.fail("a segment's sample is out of range");
  }
}

int AgvsSolver::Impl::chunk_owner(const std::vector<BatchChunk>& chunks, size_t k) const {
  // Numbered across batches, so that the work turns round the ranks; a chunk's owner may differ
  // between rank counts, its content does not. A mutation lane's chunks are its owner's, the
  // only rank that drew their points.
  const uint64_t ranks = static_cast<uint64_t>(ranks::size());
  return chunks[k].lane >= 0 ? lane_owner(static_cast<size_t>(chunks[k].lane))
                             : static_cast<int>((stats.batches * 4096 + k) % ranks);
}

void AgvsSolver::Impl::route_chunks(std::vector<BatchChunk>& chunks, const std::function<void(BatchChunk&)>& cast_chunk) {
  // Several ranks: each draws and casts the chunks it owns. Every rank learns every chunk's
  // counts (a small allgather); the segments stay with their caster, and each (segment, cell)
  // pair goes only to the rank of its cell, with the segment's objects and camera cell (an
  // all-to-all), in segment order.
  const int me = ranks::rank();
  const size_t ranks = static_cast<size_t>(ranks::size());
  std::vector<std::string> meta(chunks.size());
  std::vector<std::vector<std::vector<BatchChunk::RoutedPair>>> out(chunks.size());
  tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) {
    if (chunk_owner(chunks, k) != me) return;
    BatchChunk& c = chunks[k];
    cast_chunk(c);
    ByteWriter w;
    w.put(c.size);
    w.put(static_cast<uint32_t>(c.segs.size()));
    w.put(c.rays);
    w.put(c.pierced);
    meta[k] = w.take();
    out[k].resize(ranks);
    for (const BatchChunk::CellPair& p : c.pairs) {
      const uint32_t i = p.segment;
      out[k][static_cast<uint64_t>(p.cell) % ranks].push_back(
          {i, p.cell, {c.segs.object_a[i], c.segs.object_b[i]},
           c.camera_cell.empty() ? BatchChunk::kNotCamera : c.camera_cell[i]});
    }
    c.routed = std::move(out[k][static_cast<size_t>(me)]);
    c.pairs = {};
  });
  ranks::share(meta, [&](size_t k) { return chunk_owner(chunks, k); });
  for (size_t k = 0; k < chunks.size(); ++k) {
    BatchChunk& c = chunks[k];
    if (chunk_owner(chunks, k) == me) continue;
    ByteReader r(meta[k], "a rank's casting counts");
    const uint32_t size = r.get<uint32_t>();
    if (c.halton_count > 0 ? size > c.halton_count : size != c.size) r.fail("a chunk's sample count is wrong");
    c.size = size;
    c.segment_count = r.get<uint32_t>();
    c.rays = r.get<uint64_t>();
    c.pierced = r.get<uint64_t>();
    c.here = false;
  }
  std::vector<std::string> to(ranks);
  for (size_t q = 0; q < ranks; ++q) {
    if (q == static_cast<size_t>(me)) continue;
    ByteWriter w;
    for (size_t k = 0; k < chunks.size(); ++k) {
      if (out[k].empty() || out[k][q].empty()) continue;
      w.put(static_cast<uint64_t>(k));
      w.put_array(out[k][q]);
    }
    to[q] = w.take();
  }
  const std::vector<std::string> from = ranks::exchange(std::move(to));
  const uint32_t n_cells = cells.cell_count(), n_objects = pvs.object_count();
  for (size_t q = 0; q < ranks; ++q) {
    if (q == static_cast<size_t>(me)) continue;
    ByteReader r(from[q], "a rank's routed segments");
    while (!r.at_end()) {
      const uint64_t k = r.get<uint64_t>();
      if (k >= chunks.size() || chunk_owner(chunks, k) != static_cast<int>(q)) r.fail("a chunk from a rank not its caster");
      BatchChunk& c = chunks[k];
      r.get_array(c.routed, from[q].size());
      for (const BatchChunk::RoutedPair& p : c.routed) {
        const bool object_ok = (p.objects[0] == kNoObject || p.objects[0] < n_objects) &&
                               (p.objects[1] == kNoObject || p.objects[1] < n_objects);
        if (p.segment >= c.segment_count || p.cell < 0 || static_cast<uint32_t>(p.cell) >= n_cells ||
            !ranks::mine(static_cast<uint64_t>(p.cell)) || !object_ok ||
            (p.camera_cell != BatchChunk::kNotCamera && (p.camera_cell < -1 || p.camera_cell >= static_cast<int32_t>(n_cells))))
          r.fail("a routed segment is out of range");
      }
    }
  }
}

}  // namespace viewcells
