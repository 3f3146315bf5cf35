/// The view space interface's shared part, and the whole view box as a view space
/// (viewspace/view_space.h).
#include "viewcells/viewspace/view_space.h"

#include "viewcells/core/error.h"

namespace viewcells {

CameraSet ViewSpace::cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& config,
                             const std::function<int32_t(const Vec3&)>& cell_at, const CellLocator* locator) const {
  check_cameras(config);
  return place_cameras(scene, caster, config, cell_at, locator);
}

void ViewSpace::check_cameras(const CameraConfig& config) const {
  if (config.count == 0) throw Error("measure: the number of cameras must be positive");
  if (config.placement == CameraPlacement::kPlay && !may_know_players())
    throw Error("play cameras need a Quake 3 map (.bsp), or another view space that knows where players stand: " +
                describe() + " has no floors and spawn points to place them from");
}

namespace {

class BoxViewSpace final : public ViewSpace {
 public:
  std::string describe() const override { return "the whole view box"; }

 protected:
  CameraSet place_cameras(const Scene& scene, const RayCaster& caster, const CameraConfig& c,
                          const std::function<int32_t(const Vec3&)>& cell_at, const CellLocator* locator) const override {
    (void)cell_at;
    if (!locator) throw Error("view-box cameras need the view cells");
    CameraSet out;
    const bool closed = decide_empty_space(scene, EmptySpaceMode::kAuto).enabled;
    out.cameras = view_box_cameras(caster, *locator, c.count, c.seed, closed, out.cells);
    out.rule = std::string("uniform random points of the view box") + (closed ? " outside the solids" : "") +
               ", looking anywhere";
    return out;
  }
};

}  // namespace

std::shared_ptr<const ViewSpace> box_view_space() {
  static const std::shared_ptr<const ViewSpace> box = std::make_shared<const BoxViewSpace>();
  return box;
}

}  // namespace viewcells
