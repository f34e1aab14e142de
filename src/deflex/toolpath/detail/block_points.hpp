// The points of one motion block (a line, a subdivided line or an arc), made one at a time so that an
// arc of a hundred thousand chords costs no memory; and the arc geometry both readers build from
// their words (G-code I J K or R, APT CIRCLE/). All lengths in m.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "deflex/toolpath/toolpath_options.hpp"
#include "deflex/toolpath/toolpath_point.hpp"

namespace deflex::detail {

/// What travels with every point of a block.
struct PointContext {
  double feed_m_s = 0.0;
  double spindle_rpm = 0.0;
  SpindleState spindle = SpindleState::kOff;
  int tool = 0;
  MotionKind motion = MotionKind::kRapid;
  std::size_t line = 0;
  std::uint32_t segment = 0;
};

/// How the tool axis turns along a block.
struct AxisPath {
  enum class Kind {
    kConstant,  ///< `start` throughout
    kSlerp,     ///< along the great circle from `start` to `end` (Siemens ORIVECT's interpolation)
    kAngles,    ///< the rotary angles linear from `abc_start_rad` to `abc_end_rad`, as the axes move
  };
  Kind kind = Kind::kConstant;
  Vector3 start = Vector3::UnitZ();
  Vector3 end = Vector3::UnitZ();
  Vector3 abc_start_rad = Vector3::Zero();
  Vector3 abc_end_rad = Vector3::Zero();
  RotaryConvention rotary = RotaryConvention::kHeadHead;
};

/// A circular (or helical) arc: it turns counter-clockwise (right hand) about `normal` by `sweep_rad`
/// from the start, at a radius going linearly from `radius_start_m` to `radius_end_m`, while moving
/// `axial_m` along `normal`.
struct ArcGeometry {
  Vector3 centre_m = Vector3::Zero();  ///< in the start point's plane
  Vector3 normal = Vector3::UnitZ();   ///< unit
  Vector3 u = Vector3::UnitX();        ///< unit, from the centre towards the start
  Vector3 v = Vector3::UnitY();        ///< normal x u
  double radius_start_m = 0.0;
  double radius_end_m = 0.0;
  double sweep_rad = 0.0;  ///< in (0, 2 pi]
  double axial_m = 0.0;
};

/// An arc from its centre: `centre_m` any point on the arc's axis, `normal` the unit rotation axis
/// (counter-clockwise about it). End at the start (within 1 nm in the plane): a full circle. Returns an
/// error text (for the caller to place) when the start lies on the axis, or when the end's radius
/// differs from the start's by more than `radius_tolerance_m`.
[[nodiscard]] std::optional<std::string> arc_by_centre(const Vector3& start_m, const Vector3& end_m,
                                                       const Vector3& centre_m, const Vector3& normal,
                                                       double radius_tolerance_m, ArcGeometry& out);

/// An arc from its radius (G-code R): R > 0 the arc of at most half a turn, R < 0 the longer one,
/// turning counter-clockwise about the unit `normal`. Returns an error text when the end is at the
/// start or the chord is longer than 2 |R| by more than `radius_tolerance_m`.
[[nodiscard]] std::optional<std::string> arc_by_radius(const Vector3& start_m, const Vector3& end_m, double radius_m,
                                                       const Vector3& normal, double radius_tolerance_m,
                                                       ArcGeometry& out);

/// Chords an arc needs so that none is farther than `chord_tolerance_m` from it (sagitta
/// r (1 - cos(step / 2)) at the larger radius) and none sweeps more than 90 degrees. A double: the
/// caller refuses counts beyond toolpath_limits::kMaxPointsPerBlock before converting.
[[nodiscard]] double arc_step_count(const ArcGeometry& arc, double chord_tolerance_m);

/// The tool axis of G-code rotary angles (rad) under a machine convention (toolpath_options.hpp).
[[nodiscard]] Vector3 rotary_tool_axis(const Vector3& abc_rad, RotaryConvention rotary);

/// The unit vector a fraction `t` of the way from unit `a` to unit `b` along the great circle
/// (a and b not opposite).
[[nodiscard]] Vector3 slerp_axis(const Vector3& a, const Vector3& b, double t);

/// Thread safety: one thread at a time.
class BlockPoints {
 public:
  /// A straight move from `start_m` to `end_m` in `steps` equal steps (1: the end point only).
  void set_linear(const PointContext& context, const Vector3& start_m, const Vector3& end_m, const AxisPath& axis,
                  std::size_t steps);
  /// An arc in `steps` equal steps ending exactly at `end_m`.
  void set_arc(const PointContext& context, const ArcGeometry& arc, const Vector3& end_m, const AxisPath& axis,
               std::size_t steps);
  /// The next point of the block; false when the block has given all its points.
  bool next(ToolpathPoint& out);
  [[nodiscard]] bool done() const { return index_ >= steps_; }
  /// Points the block gives in all.
  [[nodiscard]] std::size_t steps() const { return steps_; }
  /// The fraction of the block at the last point given (k / steps).
  [[nodiscard]] double fraction() const { return fraction_; }

 private:
  [[nodiscard]] Vector3 axis_at(double t) const;

  PointContext context_;
  bool arc_ = false;
  ArcGeometry geometry_;
  Vector3 start_m_ = Vector3::Zero();
  Vector3 end_m_ = Vector3::Zero();
  AxisPath axis_;
  std::size_t steps_ = 0;
  std::size_t index_ = 0;
  double fraction_ = 0.0;
};

}  // namespace deflex::detail
