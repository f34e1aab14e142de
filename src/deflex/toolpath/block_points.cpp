// Arc geometry and the points of a motion block.
#include "deflex/toolpath/detail/block_points.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace deflex::detail {
namespace {

/// Lengths in messages: mm, to the micrometre.
std::string block_mm(double m) { return fmt::format("{:.4f} mm", m * 1e3); }

/// One nanometre: an end this close to the start (in the arc's plane) closes a full circle.
constexpr double kSamePointM = 1e-9;

}  // namespace

std::optional<std::string> arc_by_centre(const Vector3& start_m, const Vector3& end_m, const Vector3& centre_m,
                                         const Vector3& normal, double radius_tolerance_m, ArcGeometry& out) {
  out.normal = normal;
  // The centre moved along the axis into the start's plane.
  out.centre_m = centre_m + (start_m - centre_m).dot(normal) * normal;
  const Vector3 to_start = start_m - out.centre_m;
  out.radius_start_m = to_start.norm();
  if (out.radius_start_m < kSamePointM) {
    return std::string("the arc's centre is at its start point (radius 0)");
  }
  const Vector3 to_end = end_m - out.centre_m;
  out.axial_m = to_end.dot(normal);
  const Vector3 in_plane = to_end - out.axial_m * normal;
  out.radius_end_m = in_plane.norm();
  const double mismatch = std::abs(out.radius_end_m - out.radius_start_m);
  if (mismatch > radius_tolerance_m) {
    return fmt::format(
        "the arc's end is {} from its centre, its start {}: they differ by {}, more than the arc radius tolerance of "
        "{}",
        block_mm(out.radius_end_m), block_mm(out.radius_start_m), block_mm(mismatch), block_mm(radius_tolerance_m));
  }
  out.u = to_start / out.radius_start_m;
  out.v = normal.cross(out.u);
  if ((in_plane - to_start).norm() <= kSamePointM) {
    out.sweep_rad = 2.0 * kPi;
    return std::nullopt;
  }
  double angle = std::atan2(in_plane.dot(out.v), in_plane.dot(out.u));
  if (angle <= 0.0) {
    angle += 2.0 * kPi;
  }
  out.sweep_rad = angle;
  return std::nullopt;
}

std::optional<std::string> arc_by_radius(const Vector3& start_m, const Vector3& end_m, double radius_m,
                                         const Vector3& normal, double radius_tolerance_m, ArcGeometry& out) {
  const Vector3 chord_3d = end_m - start_m;
  const Vector3 chord = chord_3d - chord_3d.dot(normal) * normal;
  const double length = chord.norm();
  if (length <= kSamePointM) {
    return std::string("an arc by R whose end is its start: its centre is undefined (a full circle needs I, J, K)");
  }
  const double half = 0.5 * length;
  const double r = std::abs(radius_m);
  double h = 0.0;
  if (r < half) {
    if (half - r > radius_tolerance_m) {
      return fmt::format(
          "R {} does not reach the end point: half the chord is {}, longer than R by {}, more than the arc radius "
          "tolerance of {}",
          block_mm(radius_m), block_mm(half), block_mm(half - r), block_mm(radius_tolerance_m));
    }
  } else {
    h = std::sqrt(r * r - half * half);
  }
  // R > 0: the centre lies left of the chord seen along the rotation axis (the shorter way round).
  const Vector3 left = normal.cross(chord / length);
  const Vector3 centre = start_m + 0.5 * chord + (radius_m > 0.0 ? h : -h) * left;
  return arc_by_centre(start_m, end_m, centre, normal, radius_tolerance_m + 1e-12, out);
}

double arc_step_count(const ArcGeometry& arc, double chord_tolerance_m) {
  const double r = std::max(arc.radius_start_m, arc.radius_end_m);
  double step = toolpath_limits::kMaxArcStepRad;
  if (chord_tolerance_m < r) {
    step = std::min(step, 2.0 * std::acos(1.0 - chord_tolerance_m / r));
  }
  return std::max(1.0, std::ceil(arc.sweep_rad / step - 1e-12));
}

Vector3 rotary_tool_axis(const Vector3& abc_rad, RotaryConvention rotary) {
  using Eigen::AngleAxisd;
  if (rotary == RotaryConvention::kHeadHead) {
    return (AngleAxisd(abc_rad.z(), Vector3::UnitZ()) * AngleAxisd(abc_rad.y(), Vector3::UnitY()) *
            AngleAxisd(abc_rad.x(), Vector3::UnitX())) *
           Vector3::UnitZ();
  }
  return (AngleAxisd(-abc_rad.z(), Vector3::UnitZ()) * AngleAxisd(-abc_rad.y(), Vector3::UnitY()) *
          AngleAxisd(-abc_rad.x(), Vector3::UnitX())) *
         Vector3::UnitZ();
}

Vector3 slerp_axis(const Vector3& a, const Vector3& b, double t) {
  const double c = std::clamp(a.dot(b), -1.0, 1.0);
  const double angle = std::acos(c);
  if (angle < 1e-9) {
    return ((1.0 - t) * a + t * b).normalized();
  }
  const double s = std::sin(angle);
  return ((std::sin((1.0 - t) * angle) / s) * a + (std::sin(t * angle) / s) * b).normalized();
}

void BlockPoints::set_linear(const PointContext& context, const Vector3& start_m, const Vector3& end_m,
                             const AxisPath& axis, std::size_t steps) {
  context_ = context;
  arc_ = false;
  start_m_ = start_m;
  end_m_ = end_m;
  axis_ = axis;
  steps_ = std::max<std::size_t>(steps, 1);
  index_ = 0;
  fraction_ = 0.0;
}

void BlockPoints::set_arc(const PointContext& context, const ArcGeometry& arc, const Vector3& end_m,
                          const AxisPath& axis, std::size_t steps) {
  set_linear(context, arc.centre_m + arc.radius_start_m * arc.u, end_m, axis, steps);
  arc_ = true;
  geometry_ = arc;
}

Vector3 BlockPoints::axis_at(double t) const {
  switch (axis_.kind) {
    case AxisPath::Kind::kConstant:
      return axis_.start;
    case AxisPath::Kind::kSlerp:
      return t >= 1.0 ? axis_.end : slerp_axis(axis_.start, axis_.end, t);
    case AxisPath::Kind::kAngles:
      return rotary_tool_axis(axis_.abc_start_rad + t * (axis_.abc_end_rad - axis_.abc_start_rad), axis_.rotary);
  }
  return axis_.start;
}

bool BlockPoints::next(ToolpathPoint& out) {
  if (index_ >= steps_) {
    return false;
  }
  ++index_;
  const bool last = index_ == steps_;
  const double t = last ? 1.0 : static_cast<double>(index_) / static_cast<double>(steps_);
  if (last) {
    out.position_m = end_m_;  // the block's own end, not a sum of steps
  } else if (arc_) {
    const ArcGeometry& g = geometry_;
    const double angle = t * g.sweep_rad;
    const double r = g.radius_start_m + t * (g.radius_end_m - g.radius_start_m);
    out.position_m = g.centre_m + r * (std::cos(angle) * g.u + std::sin(angle) * g.v) + (t * g.axial_m) * g.normal;
  } else {
    out.position_m = start_m_ + t * (end_m_ - start_m_);
  }
  out.tool_axis = axis_at(t);
  out.feed_m_s = context_.feed_m_s;
  out.spindle_rpm = context_.spindle_rpm;
  out.spindle = context_.spindle;
  out.tool = context_.tool;
  out.motion = context_.motion;
  out.line = context_.line;
  out.segment = context_.segment;
  fraction_ = t;
  return true;
}

}  // namespace deflex::detail
