// The mechanistic milling force (linear edge-force model): per tooth and per axial slice, the
// tangential, radial and axial forces  b (Kc h + Ke)  with the chip h = fz sin(phi) while the tooth is
// engaged, the helix lagging each slice by z tan(helix) / R. Averaged over a revolution in closed form
// (what a robot's compensation can follow), and sampled over a tooth period for the peak the average
// leaves out (at the tooth-passing frequency N S / 60).
//
// Frames and signs (docs/machining.md, "Sign conventions"): results are in the cut frame
// (feed, normal, axis) = (f, n, a): a the tool axis from the tip into the spindle, f the feed
// direction in the plane normal to a, n = a x f (to the left of the feed seen from the spindle).
// A tooth at immersion angle phi points along  s n cos(phi) + f sin(phi), s = +1 for M3 and -1 for M4.
// Every force here is the force ON THE TOOL, which is the force on the robot; the workpiece feels the
// opposite. Moments are about the cutter's tip (the centre of its end face) unless a name says
// otherwise.
//
// Corner radius: slices below the corner radius r are treated with the corner's local edge angle
// kappa (Engin and Altintas' generalised end mill): the radial force acts along the edge's normal,
// tilted by kappa from the axis, and the edge force grows with the edge's length (dS = dz / sin kappa);
// the chip area is the flat end mill's. The coefficients are the same in the corner as on the side.
//
// Nothing here allocates or throws: the functions are for the per-point loop.
#pragma once

#include "deflex/machining/cutter.hpp"
#include "deflex/machining/cutting_coefficients.hpp"
#include "deflex/machining/engagement.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

/// The cut at one point: the cutter, its coefficients, the feed per tooth and the turning direction.
struct MillingCut {
  Cutter cutter;
  CuttingCoefficients k;
  double fz_m = 0.0;  ///< feed per tooth in the plane normal to the axis, m (feed_per_tooth_m())
  SpindleTurn turn = SpindleTurn::kClockwise;
};

/// The force and moment the cut exerts on the tool averaged over one revolution, cut frame
/// (components: feed, normal, axis).
struct MillingForce {
  Vector3 force_n = Vector3::Zero();
  /// About the tip: the in-plane force's lever along the axis, the axial force's lever at the
  /// cutter's radius and the cutting torque about the axis (which the spindle's housing, and so the
  /// robot, takes: s R Ft along the axis).
  Vector3 moment_tip_nm = Vector3::Zero();
  /// The height above the tip, along the axis, at which the in-plane force acts (the engagement's
  /// centre weighted by its force): 0 when not engaged.
  double application_height_m = 0.0;
};

/// The force averaged over a revolution, in closed form (each patch's integrals over its arc and
/// its heights; no sampling). Zero when the engagement is empty.
[[nodiscard]] MillingForce average_milling_force(const MillingCut& cut, const Engagement& engagement) noexcept;

/// The force on the tool when the spindle has turned by `rotation_rad` from the position where tooth
/// 0's tip is at immersion angle 0 (teeth equally spaced, numbered in the turning direction).
[[nodiscard]] Vector3 instantaneous_milling_force(const MillingCut& cut, const Engagement& engagement,
                                                  double rotation_rad) noexcept;

/// The largest force over a revolution (magnitude of the force vector, and that vector), from
/// `samples_per_tooth` uniform samples of one tooth period (the force repeats every tooth) plus the
/// angles where an arc's end meets a patch's end, where a force without helix jumps.
struct MillingPeak {
  double peak_force_n = 0.0;
  Vector3 force_at_peak_n = Vector3::Zero();
  double rotation_at_peak_rad = 0.0;
};
[[nodiscard]] MillingPeak peak_milling_force(const MillingCut& cut, const Engagement& engagement,
                                             int samples_per_tooth = 32) noexcept;

/// fz = F / (S N), m. Throws InputError naming the value when the feed or the spindle speed is not
/// positive and finite, or the cutter has no flutes.
[[nodiscard]] double feed_per_tooth_m(double feed_mm_min, double spindle_rpm, int flutes);

/// N S / 60, Hz.
[[nodiscard]] double tooth_passing_frequency_hz(double spindle_rpm, int flutes) noexcept;

/// The cut frame from the tool axis and the tool's velocity (any frame; the result is in the same one).
struct CutFrame {
  Vector3 feed = Vector3::UnitX();
  Vector3 normal = Vector3::UnitY();
  Vector3 axis = Vector3::UnitZ();
  /// |in-plane velocity| / |velocity|: scales a path's feed per tooth on a ramp.
  double in_plane_fraction = 1.0;
};
/// False (and `out` untouched) when the axis is not a finite non-zero vector or the motion has no
/// component normal to the axis (a plunge, which this model does not describe, or no motion).
[[nodiscard]] bool make_cut_frame(const Vector3& axis, const Vector3& velocity, CutFrame& out) noexcept;

/// The averaged wrench [F; M] in the frame the cut frame's vectors are given in, the moment taken
/// about the point `point_height_m` above the tip on the axis (0: the tip; the TCP when it sits on
/// the axis). This is the wrench on the tool, i.e. on the robot (force_model.hpp's convention once in
/// the base frame).
[[nodiscard]] Wrench milling_wrench(const MillingForce& force, const CutFrame& frame, double point_height_m) noexcept;

}  // namespace deflex
