#pragma once
// AGVS paper 4.4 (mutation-based distributions): the buffer of contributing segments that the
// two-point and silhouette mutations start from, the least mutated first.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <iterator>
#include <map>
#include <vector>

#include "viewcells/core/vec3.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/sampling/segments.h"

namespace viewcells::agvs_detail {

struct Candidate {
  Vec3 origin, term;           ///< the segment's other end, and the end where the object was seen
  double r_origin = 0, r_term = 0;  ///< radii of what lies at each end (object or view cell)
  uint32_t object = kNoObject;      ///< the object seen at `term`
};

/// A mutation strategy's candidates, the least mutated first (ties: the oldest); when full,
/// the most mutated (the newest among equals) is dropped. Kept in buckets by how often each
/// was mutated, each bucket in the order of the candidates' ids: a taken candidate moves to
/// the back of the next bucket (it is the newest there whenever the buffer was built by add()
/// and take(), so that is one step), a new one goes to the back of the first.
struct CandidateBuffer {
  struct Entry {
    uint64_t id = 0;
    Candidate candidate;
  };
  std::map<uint32_t, std::deque<Entry>> buckets;  ///< by times mutated
  size_t count = 0;
  uint64_t next_id = 0;

  bool empty() const { return count == 0; }
  size_t size() const { return count; }
  void add(const Candidate& c, size_t cap) {
    insert(0, {next_id++, c});
    if (++count > cap) {
      const auto last = std::prev(buckets.end());
      last->second.pop_back();
      if (last->second.empty()) buckets.erase(last);
      --count;
    }
  }
  /// The least mutated candidate; its count goes up by one. The reference holds until the
  /// buffer changes next.
  const Candidate& take() {
    const auto first = buckets.begin();
    const uint32_t times = first->first;
    const Entry e = first->second.front();
    first->second.pop_front();
    if (first->second.empty()) buckets.erase(first);
    return insert(times + 1, e).candidate;
  }
  /// Calls f(candidate&) for every candidate (to rewrite their objects after an edit).
  template <class F>
  void for_each(F&& f) {
    for (auto& [times, bucket] : buckets)
      for (Entry& e : bucket) f(e.candidate);
  }
  void save(ByteWriter& w) const {
    std::vector<std::pair<const Entry*, uint32_t>> all;  // in id order, with their counts
    for (const auto& [times, bucket] : buckets)
      for (const Entry& e : bucket) all.push_back({&e, times});
    std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first->id < y.first->id; });
    w.put(next_id);
    w.put<uint64_t>(all.size());
    for (const auto& [e, times] : all) {
      const Candidate& c = e->candidate;
      w.put(e->id), w.put(times);
      w.put(c.origin), w.put(c.term), w.put(c.r_origin), w.put(c.r_term), w.put(c.object);
    }
  }
  /// `box`: where candidate ends may lie (a state's candidates come from segments in the view
  /// box); `objects`: the scene's object count. Anything else is a corrupt state, refused here
  /// rather than cast (rays from 1e300 once reached Embree and aborted).
  static CandidateBuffer load(ByteReader& r, size_t cap, size_t payload, const Box3& box, uint32_t objects) {
    CandidateBuffer b;
    b.next_id = r.get<uint64_t>();
    const uint64_t n = r.get<uint64_t>();
    if (n > cap || n > payload) r.fail("too many mutation candidates");
    uint64_t previous = 0;
    for (uint64_t k = 0; k < n; ++k) {
      const uint64_t id = r.get<uint64_t>();
      const uint32_t times = r.get<uint32_t>();
      Candidate c;
      c.origin = r.get<Vec3>(), c.term = r.get<Vec3>(), c.r_origin = r.get<double>(), c.r_term = r.get<double>();
      c.object = r.get<uint32_t>();
      const bool inside = box.contains(c.origin) && box.contains(c.term);  // false for NaN
      if (!inside || !(c.r_origin >= 0 && c.r_origin < 1e300) || !(c.r_term >= 0 && c.r_term < 1e300) ||
          (c.object != kNoObject && c.object >= objects))
        r.fail("a mutation candidate lies outside the view space or names no object");
      // Saved in increasing id order (a repeat or a step back is corruption).
      if (id >= b.next_id || (k > 0 && id <= previous)) r.fail("mutation candidate ids are inconsistent");
      previous = id;
      b.insert(times, {id, c});
      ++b.count;
    }
    return b;
  }

 private:
  /// Puts `e` into bucket `times` in id order (at the back, but for a state whose history was
  /// not this buffer's own).
  Entry& insert(uint32_t times, const Entry& e) {
    std::deque<Entry>& bucket = buckets[times];
    if (bucket.empty() || bucket.back().id < e.id) return bucket.emplace_back(e);
    const auto at = std::upper_bound(bucket.begin(), bucket.end(), e.id,
                                     [](uint64_t id, const Entry& x) { return id < x.id; });
    return *bucket.insert(at, e);
  }
};

}  // namespace viewcells::agvs_detail
