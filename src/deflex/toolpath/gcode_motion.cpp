// The G-code machine's motion blocks: target, tool axis, cutting checks, lines and arcs.
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/toolpath/detail/gcode_interpreter.hpp"

namespace deflex::detail {
namespace {

bool gm_any(const GcodeWord* const (&w)[3]) { return w[0] != nullptr || w[1] != nullptr || w[2] != nullptr; }

const GcodeWord* gm_first(const GcodeWord* const (&w)[3]) {
  return w[0] != nullptr ? w[0] : w[1] != nullptr ? w[1] : w[2];
}

const char* gm_motion_name(int motion) {
  static const char* const kNames[4] = {"G0", "G1", "G2", "G3"};
  return kNames[motion];
}

}  // namespace

const GcodeWord* GcodeInterpreter::first_moving_word(const Block& b) const {
  if (b.g_motion != nullptr) return b.g_motion;
  for (const auto* group : {&b.axis, &b.rotary, &b.vector, &b.offset}) {
    if (const GcodeWord* w = gm_first(*group)) return w;
  }
  return b.r;
}

void GcodeInterpreter::count_point(const ToolpathPoint& p) {
  ++summary_.points;
  if (!summary_.multi_axis && (p.tool_axis - Vector3::UnitZ()).norm() > 1e-9) {
    summary_.multi_axis = true;
  }
}

std::size_t GcodeInterpreter::block_count(double count, const std::string& what) const {
  if (!(count <= static_cast<double>(toolpath_limits::kMaxPointsPerBlock))) {
    fail_text(
        fmt::format("{} would become {} points, more than the {} one block may give: raise the tolerance or "
                    "the step",
                    what, number_text(count), toolpath_limits::kMaxPointsPerBlock));
  }
  return static_cast<std::size_t>(count);
}

Vector3 GcodeInterpreter::block_target(const Block& b, std::array<bool, 3>& known_after) const {
  Vector3 target = position_m_;
  for (int k = 0; k < 3; ++k) {
    const GcodeWord* w = b.axis[k];
    if (w == nullptr) continue;
    const double v = w->value * length_scale();
    if (incremental_ && !known_[k]) {
      fail(w, "an incremental move (G91) on an axis whose position is not known yet");
    }
    target[k] = incremental_ ? position_m_[k] + v : v;
    known_after[k] = true;
    if (std::abs(target[k]) > toolpath_limits::kMaxCoordinateM) {
      fail(w, fmt::format("a coordinate of {} m is farther than {} m from the workpiece origin", number_text(target[k]),
                          number_text(toolpath_limits::kMaxCoordinateM)));
    }
  }
  return target;
}

PointContext GcodeInterpreter::point_context() const {
  PointContext ctx;
  ctx.feed_m_s = motion_ == 0 ? 0.0 : feed_m_s_;
  ctx.spindle_rpm = spindle_rpm_;
  ctx.spindle = spindle_;
  ctx.tool = active_tool_;
  ctx.motion = static_cast<MotionKind>(motion_);
  ctx.line = line_.number;
  ctx.segment = static_cast<std::uint32_t>(segments_);
  return ctx;
}

bool GcodeInterpreter::plan_motion(const Block& b, BlockPoints& points) {
  const bool arc = motion_ == 2 || motion_ == 3;
  if (!arc && gm_any(b.offset) && !tcp_vector_) {
    fail(gm_first(b.offset), "I, J, K belong to an arc (G2, G3), or give the tool axis under G43.5");
  }
  if (!arc && b.r != nullptr) {
    fail(b.r, "R belongs to an arc (G2, G3)");
  }
  const bool moves = gm_any(b.axis) || gm_any(b.rotary) || gm_any(b.vector) || gm_any(b.offset) || b.r != nullptr;
  if (!moves) {
    return false;
  }
  if (motion_ < 0) {
    fail(first_moving_word(b), "a coordinate with no motion mode in effect: give G0, G1, G2 or G3");
  }
  if (end_line_ != 0) {
    fail(first_moving_word(b), fmt::format("a motion after the program's end (M2/M30 on line {})", end_line_));
  }
  std::array<bool, 3> known_after = known_;
  const Vector3 target = block_target(b, known_after);
  AxisPath path;
  Vector3 abc_end_deg;
  orientation_end(b, !arc, path, abc_end_deg);
  const bool start_known = known_[0] && known_[1] && known_[2];
  const bool end_known = known_after[0] && known_after[1] && known_after[2];
  const auto finish_block = [&] {
    position_m_ = target;
    known_ = known_after;
    tool_axis_ = path.end;
    abc_deg_ = abc_end_deg;
    if (facts_.orientation != OrientationForm::kNone) axis_form_ = facts_.orientation;
  };
  if (motion_ == 0 && !end_known) {
    ++summary_.rapids_before_position_known;
    finish_block();
    return false;
  }
  if (motion_ != 0 && !start_known) {
    std::string axes;
    for (int k = 0; k < 3; ++k) {
      if (!known_[k]) axes += fmt::format("{}{}", axes.empty() ? "" : ", ", static_cast<char>('X' + k));
    }
    fail(first_moving_word(b), fmt::format("a cutting move before the position is known on {}: the program's first "
                                           "moves must give X, Y and Z",
                                           axes));
  }
  if (motion_ != 0) check_cutting(b, motion_);
  if (segments_ > std::numeric_limits<std::uint32_t>::max()) {
    fail_text("more than 4294967296 motion blocks");
  }
  const PointContext ctx = point_context();
  facts_.motion_g = motion_;
  facts_.incremental = incremental_;
  facts_.units = units_;
  if (arc) {
    plan_arc(b, motion_, target, ctx, path, points);
  } else {
    std::size_t steps = 1;
    if (motion_ == 1 && options_.max_linear_step_m > 0.0) {
      const double length = (target - position_m_).norm();
      steps = block_count(std::max(1.0, std::ceil(length / options_.max_linear_step_m - 1e-9)), "a linear move");
    }
    points.set_linear(ctx, position_m_, target, path, steps);
  }
  finish_block();
  ++segments_;
  ++summary_.motion_blocks;
  if (first_point_) {
    summary_.units = units_;
    summary_.plane = plane_;
    first_point_ = false;
  }
  return true;
}

void GcodeInterpreter::orientation_end(const Block& b, bool linear, AxisPath& path, Vector3& abc_end_deg) {
  path = AxisPath{};
  path.start = path.end = tool_axis_;
  path.rotary = options_.rotary;
  abc_end_deg = abc_deg_;
  const bool by_vector = gm_any(b.vector);
  const bool by_ijk = linear && tcp_vector_ && gm_any(b.offset);
  facts_.orientation = OrientationForm::kNone;
  facts_.vector_by_ijk = by_ijk;
  if (by_vector && by_ijk) {
    fail(gm_first(b.vector), "the tool axis given twice (A3= B3= C3= and I J K)");
  }
  if ((by_vector || by_ijk) && gm_any(b.rotary)) {
    fail(gm_first(b.rotary), "rotary angles (A B C) and a tool-axis vector in one block");
  }
  if (by_vector || by_ijk) {
    const auto& c = by_vector ? b.vector : b.offset;
    if (by_vector && !traori_) {
      fail(gm_first(c),
           "A3= B3= C3= give the tool axis under TRAORI (Siemens' 5-axis transformation), and no TRAORI "
           "comes before them");
    }
    for (int k = 0; k < 3; ++k) {
      if (c[k] == nullptr) {
        fail(gm_first(c), by_vector ? "a tool-axis vector needs all three of A3=, B3=, C3="
                                    : "a tool-axis vector (G43.5) needs all three of I, J, K");
      }
    }
    const Vector3 v(c[0]->value, c[1]->value, c[2]->value);
    if (!(v.norm() > 1e-9)) {
      fail(c[0], "a tool-axis vector of length 0");
    }
    path.end = v.normalized();
    facts_.orientation = OrientationForm::kVector;
  } else if (gm_any(b.rotary)) {
    for (int k = 0; k < 3; ++k) {
      if (b.rotary[k] == nullptr) continue;
      abc_end_deg[k] = incremental_ ? abc_deg_[k] + b.rotary[k]->value : b.rotary[k]->value;
      if (std::abs(abc_end_deg[k]) > 3600.0) {
        fail(b.rotary[k], "a rotary angle outside -3600..3600 degrees");
      }
    }
    path.end = rotary_tool_axis(abc_end_deg * (kPi / 180.0), options_.rotary);
    facts_.orientation = OrientationForm::kAngles;
  }
  facts_.abc_start_deg = abc_deg_;
  facts_.abc_end_deg = abc_end_deg;
  const bool angles_move = facts_.orientation == OrientationForm::kAngles && abc_end_deg != abc_deg_;
  if (angles_move && axis_form_ != OrientationForm::kVector) {
    path.kind = AxisPath::Kind::kAngles;
    path.abc_start_rad = abc_deg_ * (kPi / 180.0);
    path.abc_end_rad = abc_end_deg * (kPi / 180.0);
  } else if ((path.end - path.start).norm() > 1e-12) {
    if (path.start.dot(path.end) < -1.0 + 1e-9) {
      fail(first_moving_word(b), "the tool axis turns half a turn in one block: which way it turns is undefined");
    }
    path.kind = AxisPath::Kind::kSlerp;
  }
  facts_.orientation_changes = path.kind != AxisPath::Kind::kConstant;
}

void GcodeInterpreter::check_cutting(const Block& b, int motion) const {
  const char* g = gm_motion_name(motion);
  if (!(feed_m_s_ > 0.0)) {
    fail_word(b.f != nullptr ? b.f->text(line_.text) : "F",
              feed_line_ == 0 ? fmt::format("a cutting move ({}) with no feed: no F word has set one", g)
                              : fmt::format("a cutting move ({}) at feed 0 (F0 on line {})", g, feed_line_));
  }
  if (spindle_ == SpindleState::kOff) {
    fail_word(b.m_spindle != nullptr   ? b.m_spindle->text(line_.text)
              : spindle_off_line_ != 0 ? "M5"
                                       : "M3",
              spindle_off_line_ != 0
                  ? fmt::format("a cutting move ({}) with the spindle stopped (M5 on line {})", g, spindle_off_line_)
                  : fmt::format("a cutting move ({}) before any M3 or M4 has started the spindle", g));
  }
  if (!(spindle_rpm_ > 0.0)) {
    fail_word(b.s != nullptr ? b.s->text(line_.text) : "S",
              spindle_rpm_line_ == 0
                  ? fmt::format("a cutting move ({}) with no spindle speed: no S word has set one", g)
                  : fmt::format("a cutting move ({}) at spindle speed 0 (S0 on line {})", g, spindle_rpm_line_));
  }
}

void GcodeInterpreter::plan_arc(const Block& b, int motion, const Vector3& target, const PointContext& context,
                                const AxisPath& axis, BlockPoints& points) {
  // The plane's axes (first, second) and its normal: G17 X Y (Z), G18 Z X (Y), G19 Y Z (X).
  static const int kAxes[3][3] = {{0, 1, 2}, {2, 0, 1}, {1, 2, 0}};
  static const char* const kPlaneNames[3] = {"G17", "G18", "G19"};
  const int p = static_cast<int>(plane_);
  const int first = kAxes[p][0], second = kAxes[p][1], normal_axis = kAxes[p][2];
  if (b.offset[normal_axis] != nullptr) {
    fail(b.offset[normal_axis], fmt::format("{} is not an arc offset in the {} plane (I, J, K of its two axes are)",
                                            static_cast<char>('I' + normal_axis), kPlaneNames[p]));
  }
  // G2 turns clockwise seen from the normal's positive side: counter-clockwise about -normal.
  Vector3 normal = Vector3::Zero();
  normal[normal_axis] = motion == 3 ? 1.0 : -1.0;
  ArcGeometry g;
  std::optional<std::string> error;
  const GcodeWord* named = b.r;
  if (b.r != nullptr) {
    if (b.offset[first] != nullptr || b.offset[second] != nullptr) {
      fail(b.r, "an arc by R and by I, J, K at once");
    }
    if (b.r->value == 0.0) {
      fail(b.r, "an arc of radius 0");
    }
    if (std::abs(b.r->value * length_scale()) > toolpath_limits::kMaxCoordinateM) {
      fail(b.r, "an arc radius beyond 100 m");
    }
    error = arc_by_radius(position_m_, target, b.r->value * length_scale(), normal, options_.arc_radius_tolerance_m, g);
  } else {
    named = b.offset[first] != nullptr ? b.offset[first] : b.offset[second];
    if (named == nullptr) {
      fail(first_moving_word(b), "an arc with neither I, J, K nor R");
    }
    Vector3 centre = position_m_;
    for (const int k : {first, second}) {
      if (arc_centre_absolute_ && b.offset[k] == nullptr) {
        fail(named, "an arc centre under G90.1 (absolute) needs both of its plane's coordinates");
      }
      const double v = b.offset[k] != nullptr ? b.offset[k]->value * length_scale() : 0.0;
      centre[k] = arc_centre_absolute_ ? v : position_m_[k] + v;
      if (std::abs(centre[k]) > toolpath_limits::kMaxCoordinateM) {
        fail(b.offset[k], "an arc centre farther than 100 m from the workpiece origin");
      }
    }
    error = arc_by_centre(position_m_, target, centre, normal, options_.arc_radius_tolerance_m, g);
  }
  if (error) {
    fail(named, *error);
  }
  const std::size_t steps = block_count(arc_step_count(g, options_.chord_tolerance_m), "an arc");
  points.set_arc(context, g, target, axis, steps);
  ++summary_.arcs;
}

}  // namespace deflex::detail
