#pragma once
// AGVS paper 4.4 (mutation-based distributions): the buffer of contributing segments that the
// two-point and silhouette mutations start from, the least mutated first.
#include <cstdint>
#include <iterator>
#include <map>
#include <set>

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
/// the most mutated (the newest among equals) is dropped.
struct CandidateBuffer {
  std::map<uint64_t, Candidate> candidates;
  std::set<std::pair<uint32_t, uint64_t>> by_count;
  std::map<uint64_t, uint32_t> count_of;
  uint64_t next_id = 0;

  bool empty() const { return by_count.empty(); }
  size_t size() const { return candidates.size(); }
  void add(const Candidate& c, size_t cap) {
    const uint64_t id = next_id++;
    candidates.emplace(id, c);
    by_count.insert({0u, id});
    count_of[id] = 0;
    if (candidates.size() > cap) {
      const auto last = std::prev(by_count.end());
      candidates.erase(last->second);
      count_of.erase(last->second);
      by_count.erase(last);
    }
  }
  /// The least mutated candidate; its count goes up by one.
  const Candidate& take() {
    const auto first = *by_count.begin();
    by_count.erase(by_count.begin());
    by_count.insert({first.first + 1, first.second});
    count_of[first.second] = first.first + 1;
    return candidates.at(first.second);
  }
  void save(ByteWriter& w) const {
    w.put(next_id);
    w.put<uint64_t>(candidates.size());
    for (const auto& [id, c] : candidates) {
      w.put(id), w.put(count_of.at(id));
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
    for (uint64_t k = 0; k < n; ++k) {
      const uint64_t id = r.get<uint64_t>();
      const uint32_t count = r.get<uint32_t>();
      Candidate c;
      c.origin = r.get<Vec3>(), c.term = r.get<Vec3>(), c.r_origin = r.get<double>(), c.r_term = r.get<double>();
      c.object = r.get<uint32_t>();
      const bool inside = box.contains(c.origin) && box.contains(c.term);  // false for NaN
      if (!inside || !(c.r_origin >= 0 && c.r_origin < 1e300) || !(c.r_term >= 0 && c.r_term < 1e300) ||
          (c.object != kNoObject && c.object >= objects))
        r.fail("a mutation candidate lies outside the view space or names no object");
      if (id >= b.next_id || !b.candidates.emplace(id, c).second) r.fail("mutation candidate ids are inconsistent");
      b.count_of[id] = count;
      b.by_count.insert({count, id});
    }
    return b;
  }
};

}  // namespace viewcells::agvs_detail
