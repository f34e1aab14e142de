// Where the cutter's teeth are in the material: immersion arcs and the axial band each covers, as a
// stock query (stock.hpp) or a fixed radial width and depth (uniform_engagement()) gives them, and
// the force model (milling_force.hpp) takes them. Fixed capacity: building and reading one never
// allocates.
//
// Angles (docs/machining.md, "Sign conventions"): the immersion angle phi of a tooth is measured in
// the plane normal to the tool axis, in the spindle's turning direction, from the side the teeth come
// from (phi = 0) through the feed direction (phi = pi/2) to the side they go to (phi = pi). A tooth
// at phi cuts a chip h = fz sin(phi), so only 0 <= phi <= pi cuts; an arc that starts at 0 is
// up (conventional) milling, one that ends at pi down (climb) milling, 0..pi a full slot.
#pragma once

#include <array>

#include "deflex/model/types.hpp"

namespace deflex {

/// +1 for M3, -1 for M4: the sign of the normal axis in the immersion angle (milling_force.hpp). The
/// spindle's direction is SpindleTurn (model/types.hpp, shared with the toolpath); a cut is given
/// kClockwise or kCounterClockwise (kOff, a program's stopped spindle, cuts nothing and counts as M4
/// here).
[[nodiscard]] inline constexpr double turn_sign(SpindleTurn t) { return t == SpindleTurn::kClockwise ? 1.0 : -1.0; }

/// One engaged region of the cutter: teeth cut between the immersion angles entry_rad..exit_rad
/// (0 <= entry < exit <= pi) over the heights z_lo_m..z_hi_m above the tip, along the tool axis.
struct EngagementPatch {
  double entry_rad = 0.0;
  double exit_rad = 0.0;
  double z_lo_m = 0.0;
  double z_hi_m = 0.0;
};

/// The engaged regions, and a one-arc summary of them for outputs: ae_m the radial width between the
/// first entry and the last exit measured normal to the feed, R (cos entry - cos exit); ap_m the
/// deepest engaged height above the tip. Several patches are the per-slice arcs of an engagement that
/// is not one arc (a step, a boss, a sloped floor); the force model integrates each one.
struct Engagement {
  static constexpr int kMaxPatches = 48;
  std::array<EngagementPatch, kMaxPatches> patches{};
  int count = 0;
  double ae_m = 0.0;
  double ap_m = 0.0;
  double entry_rad = 0.0;
  double exit_rad = 0.0;

  [[nodiscard]] bool engaged() const { return count > 0; }
  /// Adds a patch (empty ones are dropped); false when full (the caller merges or stops).
  bool add(const EngagementPatch& p) noexcept;
  /// Sets ae_m, ap_m, entry_rad and exit_rad from the patches for a cutter of radius `radius_m`.
  void summarise(double radius_m) noexcept;
  void clear() noexcept { *this = Engagement(); }
};

/// Which side of the cutter the material is on, for an engagement given by its width alone.
enum class CutSide {
  kConventional,  ///< up milling: the arc starts at phi = 0
  kClimb,         ///< down milling: the arc ends at phi = pi
};

/// The entry and exit angles of a radial width ae on a cutter of diameter D (closed form):
/// conventional 0 .. acos(1 - 2 ae / D), climb pi - acos(1 - 2 ae / D) .. pi; ae >= D is a full slot.
void immersion_angles(double ae_m, double diameter_m, CutSide side, double& entry_rad, double& exit_rad) noexcept;

/// One patch: the radial width ae_m on `side` over the axial depth ap_m from the tip (the ae_mm=,
/// ap_mm= overrides, a slot of a known depth). ae_m and ap_m must be positive.
[[nodiscard]] Engagement uniform_engagement(double ae_m, double ap_m, double diameter_m, CutSide side) noexcept;

}  // namespace deflex
