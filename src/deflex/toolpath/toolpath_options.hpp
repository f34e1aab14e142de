// The choices a toolpath reader leaves to its caller (arc interpolation, the machine's rotary-axis
// convention, the G-code dialect) and the fixed limits every point is held to. docs/machining.md.
#pragma once

#include <string>

#include "deflex/toolpath/toolpath_point.hpp"

namespace deflex {

/// How G-code's A, B, C angles (degrees) give the tool axis in the workpiece frame. Both read X, Y, Z
/// as the tool tip in the workpiece frame, which is what a 5-axis post writes with tool centre point
/// control on (Fanuc G43.4, Siemens TRAORI, Heidenhain M128/TCPM); a post for a machine without it
/// writes machine-axis positions that no convention can read.
enum class RotaryConvention {
  /// Head-head: the spindle head carries the rotations, the outer (C about z) carrying the inner
  /// (B about y, A about x): axis = Rz(C) Ry(B) Rx(A) (0,0,1). A machine with only A and C, or only
  /// B and C, is this with the missing angle 0.
  kHeadHead,
  /// Table-table: the tilting table (A about x, or B about y) carries the rotary table (C about z)
  /// that carries the part, with the spindle fixed along the machine's z. The part turns by
  /// Rx(A) Ry(B) Rz(C), so the axis seen from the part is Rz(-C) Ry(-B) Rx(-A) (0,0,1).
  kTableTable,
};

/// Words whose meaning differs between controls.
enum class GcodeDialect {
  kIso,      ///< ISO 6983 / Fanuc: G20/G21 select inch/mm; G70, G71 are refused
  kSiemens,  ///< Sinumerik 840D: G70/G700 inch and G71/G710 mm, besides G20/G21
};

struct ToolpathOptions {
  /// Arcs become chords no farther than this from the arc (the sagitta), m. 1e-7..1e-3 m.
  double chord_tolerance_m = 1e-5;
  /// An arc whose end point lies farther from its centre than its start (by I J K), or whose chord is
  /// longer than 2 R (by R), by more than this is refused, m. 1e-7..1e-3 m.
  double arc_radius_tolerance_m = 1e-5;
  /// Linear feed moves (G1, GOTO) longer than this are given as equal steps no longer than it, so that
  /// a force or deflection that varies along a long cut is followed; 0 keeps one point a block, m.
  /// 0 or 1e-5..1 m.
  double max_linear_step_m = 0.0;
  RotaryConvention rotary = RotaryConvention::kHeadHead;
  GcodeDialect dialect = GcodeDialect::kIso;
  /// APT/CL data without UNITS/ (NX's CLSF never writes it) is in this unit.
  LengthUnit apt_default_units = LengthUnit::kMillimetre;
};

/// Throws InputError naming the field when an option is outside its range.
void check_toolpath_options(const ToolpathOptions& options);

/// The options from the command line's "chord_mm=0.01,arc_tolerance_mm=0.01,step_mm=1,
/// rotary=head-head|table-table,dialect=iso|siemens,apt_units=mm|inch" (every key optional; step_mm=0
/// keeps one point a linear block), checked. Throws InputError quoting the spec and naming the key.
[[nodiscard]] ToolpathOptions parse_toolpath_options_spec(const std::string& spec);

namespace toolpath_limits {
/// A coordinate farther than this from the workpiece origin is refused (a typo or a unit slip): m.
inline constexpr double kMaxCoordinateM = 100.0;
/// The largest programmed feed accepted, mm/min (100 m/min: above the fastest milling machines).
inline constexpr double kMaxFeedMmPerMin = 100000.0;
/// The largest spindle speed accepted, rev/min.
inline constexpr double kMaxSpindleRpm = 100000.0;
/// The most points one block may become (an arc at a fine chord tolerance, a long subdivided move).
inline constexpr std::size_t kMaxPointsPerBlock = 1'000'000;
/// The most different tools a program may name.
inline constexpr std::size_t kMaxTools = 10000;
/// The longest line read, bytes.
inline constexpr std::size_t kMaxLineBytes = 65536;
/// The sweep of one arc step never exceeds this, whatever the chord tolerance, rad (90 degrees).
inline constexpr double kMaxArcStepRad = 1.5707963267948966;
}  // namespace toolpath_limits

}  // namespace deflex
