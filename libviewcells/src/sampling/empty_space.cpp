/// Whether empty view space detection may run (view-cell-construction paper, section 4.1,
/// figure 5): only when every object is a closed, consistently and outward oriented solid, so
/// that a ray meeting a back face first starts inside one. The decision in words, for reports.
#include <string>

#include "viewcells/core/error.h"
#include "viewcells/sampling/sampler.h"

namespace viewcells {

EmptySpaceMode parse_empty_space_mode(const std::string& s) {
  if (s == "auto") return EmptySpaceMode::kAuto;
  if (s == "on") return EmptySpaceMode::kOn;
  if (s == "off") return EmptySpaceMode::kOff;
  throw Error("unknown empty-space mode '" + s + "' (expected auto, on or off)");
}

EmptySpaceDecision decide_empty_space(const Scene& scene, EmptySpaceMode mode) {
  size_t open = 0, inconsistent = 0, inward = 0;
  std::string example;
  for (const ObjectInfo& o : scene.objects) {
    if (o.solid()) continue;
    const char* why = !o.closed ? "open" : (!o.oriented ? "inconsistently oriented" : "normals point inwards");
    (!o.closed ? open : (!o.oriented ? inconsistent : inward))++;
    if (example.empty()) example = "'" + o.name + "' is " + why;
  }
  const size_t bad = open + inconsistent + inward;
  const std::string n = std::to_string(scene.objects.size());
  EmptySpaceDecision d;
  switch (mode) {
    case EmptySpaceMode::kOff:
      d = {false, "disabled by the user"};
      break;
    case EmptySpaceMode::kOn:
      d = {true, bad ? "enabled by the user although " + std::to_string(bad) + " of " + n +
                           " objects are not closed outward-oriented solids (" + example + ")"
                     : "enabled by the user; all " + n + " objects are closed outward-oriented solids"};
      break;
    case EmptySpaceMode::kAuto:
      d = bad ? EmptySpaceDecision{false, "disabled: " + std::to_string(bad) + " of " + n +
                                              " objects are not closed outward-oriented solids (" +
                                              std::to_string(open) + " open, " + std::to_string(inconsistent) +
                                              " inconsistently oriented, " + std::to_string(inward) +
                                              " inward; e.g. " + example + ")"}
              : EmptySpaceDecision{true, "enabled: all " + n +
                                             " objects are closed, consistently oriented and outward facing"};
      break;
  }
  return d;
}

}  // namespace viewcells
