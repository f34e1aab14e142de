// APT/CL motion records: GOTO lines and CIRCLE arcs into points.
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/toolpath/detail/apt_interpreter.hpp"

namespace deflex::detail {

void AptInterpreter::circle_record() {
  need_args(7, 11);
  if (rapid_) {
    fail("an arc after RAPID: deflex reads arcs at the feed");
  }
  for (int k = 0; k < 3; ++k) {
    circle_centre_m_[k] = number(static_cast<std::size_t>(k)) * length_scale();
    if (std::abs(circle_centre_m_[k]) > toolpath_limits::kMaxCoordinateM) {
      fail_arg(static_cast<std::size_t>(k), "a centre farther than 100 m from the workpiece origin");
    }
  }
  if (!read_axis_arg(3, circle_axis_)) fail("needs the axis i, j, k");
  circle_radius_m_ = number(6) * length_scale();
  if (!(circle_radius_m_ > 0.0) || circle_radius_m_ > toolpath_limits::kMaxCoordinateM) {
    fail_arg(6, "a radius outside 0..100 m");
  }
  for (std::size_t i = 7; i < record_->args.size(); ++i) {
    (void)number(i);  // CAM tolerances (NX: tolerance, thickness, ...): numbers that do not change the arc
  }
  circle_ = true;
  circle_used_ = false;
  circle_line_ = record_->line;
}

void AptInterpreter::check_cutting() const {
  if (!(feed_m_s_ > 0.0)) {
    fail(feed_line_ == 0
             ? std::string("a cutting move (GOTO without RAPID) with no feed: no FEDRAT has set one")
             : fmt::format("a cutting move (GOTO without RAPID) at feed 0 (FEDRAT on line {})", feed_line_));
  }
  if (spindle_ == SpindleState::kOff) {
    fail(spindle_off_line_ != 0
             ? fmt::format("a cutting move with the spindle stopped (SPINDL/OFF on line {})", spindle_off_line_)
             : std::string("a cutting move before any SPINDL has started the spindle"));
  }
  if (!(spindle_rpm_ > 0.0)) {
    fail("a cutting move at spindle speed 0");
  }
}

bool AptInterpreter::goto_record(BlockPoints& points) {
  const std::size_t n = record_->args.size();
  if (n != 3 && n != 6) {
    fail(fmt::format("takes x, y, z or x, y, z, i, j, k, not {} arguments", n));
  }
  Vector3 target;
  for (int k = 0; k < 3; ++k) {
    target[k] = number(static_cast<std::size_t>(k)) * length_scale();
    if (std::abs(target[k]) > toolpath_limits::kMaxCoordinateM) {
      fail_arg(static_cast<std::size_t>(k), fmt::format("a coordinate of {} m is farther than 100 m from the "
                                                        "workpiece origin",
                                                        number_text(target[k])));
    }
  }
  Vector3 axis_end = tool_axis_;
  (void)read_axis_arg(3, axis_end);
  const bool rapid = rapid_;
  rapid_ = false;
  if (!rapid) check_cutting();
  if (segments_ > std::numeric_limits<std::uint32_t>::max()) fail("more than 4294967296 motion records");
  AxisPath path;
  path.start = tool_axis_;
  path.end = axis_end;
  if ((axis_end - tool_axis_).norm() > 1e-12) {
    if (axis_end.dot(tool_axis_) < -1.0 + 1e-9) {
      fail("the tool axis turns half a turn in one move: which way it turns is undefined");
    }
    path.kind = AxisPath::Kind::kSlerp;
  }
  PointContext ctx;
  ctx.feed_m_s = rapid ? 0.0 : feed_m_s_;
  ctx.spindle_rpm = spindle_rpm_;
  ctx.spindle = spindle_;
  ctx.tool = tool_;
  ctx.motion = rapid ? MotionKind::kRapid : MotionKind::kLinear;
  ctx.line = record_->line;
  ctx.segment = static_cast<std::uint32_t>(segments_);
  const auto count = [this](double c) {
    if (!(c <= static_cast<double>(toolpath_limits::kMaxPointsPerBlock))) {
      fail(fmt::format("would become {} points, more than the {} one move may give: raise the tolerance or the step",
                       number_text(c), toolpath_limits::kMaxPointsPerBlock));
    }
    return static_cast<std::size_t>(c);
  };
  if (circle_) {
    if (!position_known_)
      fail(fmt::format("the CIRCLE of line {} has no start: no GOTO or FROM before it", circle_line_));
    ArcGeometry g;
    if (const auto error =
            arc_by_centre(position_m_, target, circle_centre_m_, circle_axis_, options_.arc_radius_tolerance_m, g)) {
      fail(*error);
    }
    if (std::abs(g.radius_start_m - circle_radius_m_) > options_.arc_radius_tolerance_m) {
      fail(fmt::format("the arc starts {:.4f} mm from the centre of the CIRCLE of line {}, whose radius is {:.4f} mm",
                       g.radius_start_m * 1e3, circle_line_, circle_radius_m_ * 1e3));
    }
    ctx.motion = circle_axis_.dot(path.start) >= 0.0 ? MotionKind::kArcCcw : MotionKind::kArcCw;
    points.set_arc(ctx, g, target, path, count(arc_step_count(g, options_.chord_tolerance_m)));
    circle_used_ = true;
    ++summary_.arcs;
  } else {
    std::size_t steps = 1;
    if (!rapid && position_known_ && options_.max_linear_step_m > 0.0) {
      steps = count(std::max(1.0, std::ceil((target - position_m_).norm() / options_.max_linear_step_m - 1e-9)));
    }
    points.set_linear(ctx, position_known_ ? position_m_ : target, target, path, steps);
  }
  position_m_ = target;
  position_known_ = true;
  tool_axis_ = axis_end;
  ++segments_;
  ++summary_.motion_blocks;
  if (first_point_) {
    summary_.units = units_;
    first_point_ = false;
  }
  return true;
}

void AptInterpreter::finish() {
  if (circle_ && !circle_used_) {
    throw DataError(fmt::format("{}:{}: record 'CIRCLE': no GOTO follows it", source_, circle_line_));
  }
}

}  // namespace deflex::detail
