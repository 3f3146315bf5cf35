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
#include "viewcells/core/cluster.h"

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
  if (cluster::size() > 1) {
    // Several ranks: each draws and casts the chunks it owns (numbered across batches, so that
    // the work turns round the ranks; a chunk's owner may differ between rank counts, its
    // content does not), and every rank receives all chunks. A mutation lane's chunks are its
    // owner's, the only rank that drew their points. A chunk's pairs travel sorted by the rank
    // of their cell: each rank keeps its own.
    std::vector<std::string> items(chunks.size());
    const uint64_t base = stats.batches * 4096;
    const uint64_t ranks = static_cast<uint64_t>(cluster::size());
    auto owner = [&](size_t k) {
      return chunks[k].lane >= 0 ? lane_owner(static_cast<size_t>(chunks[k].lane)) : static_cast<int>((base + k) % ranks);
    };
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) {
      if (owner(k) != cluster::rank()) return;
      BatchChunk& c = chunks[k];
      cast_chunk(c);
      ByteWriter w;
      w.put(c.size);
      w.put(c.rays);
      w.put_array(c.sample_of);
      put_segments(w, c.segs);
      w.put_array(c.camera_cell);
      w.put(c.pierced);
      std::vector<std::vector<BatchChunk::CellPair>> of_rank(ranks);
      for (const BatchChunk::CellPair& p : c.pairs) of_rank[static_cast<uint64_t>(p.cell) % ranks].push_back(p);
      for (const auto& pairs : of_rank) w.put_array(pairs);
      items[k] = w.take();
    });
    cluster::share(items, owner);
    for (size_t k = 0; k < chunks.size(); ++k) {
      BatchChunk& c = chunks[k];
      ByteReader r(items[k], "a rank's casting results");
      const uint32_t size = r.get<uint32_t>();
      if (c.halton_count > 0 ? size > c.halton_count : size != c.size) r.fail("a chunk's sample count is wrong");
      c.size = size;
      c.rays = r.get<uint64_t>();
      r.get_array(c.sample_of, items[k].size());
      get_segments(r, c.segs, items[k].size());
      if (c.sample_of.size() != c.segs.size()) r.fail("a chunk's segments and samples differ in number");
      for (uint32_t sample : c.sample_of)
        if (sample >= c.size) r.fail("a segment's sample is out of range");
      r.get_array(c.camera_cell, items[k].size());
      if (!c.camera_cell.empty() && (c.dist != kVsd || c.camera_cell.size() != c.segs.size()))
        r.fail("a chunk's camera segments are wrong");
      for (int32_t cell : c.camera_cell)
        if (cell != BatchChunk::kNotCamera && (cell < -1 || cell >= static_cast<int32_t>(cells.cell_count())))
          r.fail("a camera's cell is out of range");
      c.pierced = r.get<uint64_t>();
      std::vector<BatchChunk::CellPair> pairs;
      for (uint64_t rank = 0; rank < ranks; ++rank) {
        r.get_array(pairs, items[k].size());
        if (rank != static_cast<uint64_t>(cluster::rank())) continue;
        for (const BatchChunk::CellPair& p : pairs)
          if (p.segment >= c.segs.size() || p.cell < 0 || static_cast<uint32_t>(p.cell) >= cells.cell_count() ||
              !cluster::mine(static_cast<uint64_t>(p.cell)))
            r.fail("a segment's cell is out of range");
        c.pairs = std::move(pairs);
      }
    }
  } else {
    tbb::parallel_for(size_t{0}, chunks.size(), [&](size_t k) { cast_chunk(chunks[k]); });
  }
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
    total += c.segs.size();
  }
  return chunks;
}

/// What applying a batch counted: per distribution, and the estimator's camera rays per sample
/// (0 when the sample's point is inside a solid: no camera stands there) and those that were
/// wrong pixels (an entry new to the point's cell).

}  // namespace viewcells
