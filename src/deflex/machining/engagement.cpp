// Engagement patches and their summary.
#include "deflex/machining/engagement.hpp"

#include <algorithm>
#include <cmath>

#include "deflex/model/types.hpp"

namespace deflex {

bool Engagement::add(const EngagementPatch& p) noexcept {
  if (!(p.exit_rad > p.entry_rad) || !(p.z_hi_m > p.z_lo_m)) {
    return true;
  }
  if (count >= kMaxPatches) {
    return false;
  }
  patches[static_cast<std::size_t>(count++)] = p;
  return true;
}

void Engagement::summarise(double radius_m) noexcept {
  ae_m = ap_m = entry_rad = exit_rad = 0.0;
  if (count == 0) {
    return;
  }
  entry_rad = kPi;
  for (int i = 0; i < count; ++i) {
    const EngagementPatch& p = patches[static_cast<std::size_t>(i)];
    entry_rad = std::min(entry_rad, p.entry_rad);
    exit_rad = std::max(exit_rad, p.exit_rad);
    ap_m = std::max(ap_m, p.z_hi_m);
  }
  ae_m = radius_m * (std::cos(entry_rad) - std::cos(exit_rad));
}

void immersion_angles(double ae_m, double diameter_m, CutSide side, double& entry_rad, double& exit_rad) noexcept {
  const double c = std::clamp(1.0 - 2.0 * ae_m / diameter_m, -1.0, 1.0);
  const double sweep = std::acos(c);
  if (side == CutSide::kConventional) {
    entry_rad = 0.0;
    exit_rad = sweep;
  } else {
    entry_rad = kPi - sweep;
    exit_rad = kPi;
  }
}

Engagement uniform_engagement(double ae_m, double ap_m, double diameter_m, CutSide side) noexcept {
  Engagement e;
  EngagementPatch p;
  immersion_angles(ae_m, diameter_m, side, p.entry_rad, p.exit_rad);
  p.z_lo_m = 0.0;
  p.z_hi_m = ap_m;
  e.add(p);
  e.summarise(0.5 * diameter_m);
  return e;
}

}  // namespace deflex
