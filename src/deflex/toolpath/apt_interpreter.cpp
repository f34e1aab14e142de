// APT/CL records given their meaning: motion, feed, spindle, tools, arcs.
#include "deflex/toolpath/detail/apt_interpreter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::detail {
namespace {

/// Records read and left without effect on the points: names, display, CAM tolerances, coolant, stops.
bool ai_no_effect(const std::string& m) {
  static const char* const kNames[] = {"PARTNO", "PPRINT", "REMARK", "PAINT", "TOOL PATH",   "MACHIN",
                                       "COOLNT", "INTOL",  "OUTTOL", "TOLER", "END-OF-PATH", "OPSTOP",
                                       "STOP",   "DELAY",  "MSYS",   "SELECT"};
  return std::any_of(std::begin(kNames), std::end(kNames), [&](const char* n) { return m == n; });
}

constexpr const char* kAptRecordsRead =
    "GOTO, FROM, RAPID, CIRCLE, FEDRAT, SPINDL, CUTTER, TLDATA, LOADTL, LOAD, TLAXIS, MULTAX, UNITS, FINI, and "
    "without effect PARTNO, PPRINT, PAINT, TOOL PATH, MACHIN, COOLNT, INTOL, OUTTOL, TOLER, MSYS, SELECT, DELAY, "
    "STOP, OPSTOP, END-OF-PATH, CUTCOM/OFF, CYCLE/OFF";

}  // namespace

AptInterpreter::AptInterpreter(std::string source, const ToolpathOptions& options)
    : source_(std::move(source)), options_(options), units_(options.apt_default_units) {
  check_toolpath_options(options_);
  summary_.format = ToolpathFormat::kApt;
  summary_.source = source_;
  summary_.units = units_;
}

void AptInterpreter::fail(const std::string& what) const {
  throw DataError(fmt::format("{}:{}: record '{}': {}", source_, record_->line, record_->major, what));
}

void AptInterpreter::fail_arg(std::size_t i, const std::string& what) const {
  throw DataError(fmt::format("{}:{}: record '{}', argument {} '{}': {}", source_, record_->line, record_->major, i + 1,
                              record_->args[i], what));
}

bool AptInterpreter::is_number(std::size_t i) const { return parse_double(record_->args[i]).has_value(); }

double AptInterpreter::number(std::size_t i) const {
  const std::optional<double> v = parse_double(record_->args[i]);
  if (!v) {
    fail_arg(i, not_a_number(record_->args[i]));
  }
  if (std::abs(*v) > 1e12) {
    fail_arg(i, "a value beyond 1e12");
  }
  return *v;
}

void AptInterpreter::need_args(std::size_t min, std::size_t max) const {
  const std::size_t n = record_->args.size();
  if (n < min || n > max) {
    fail(min == max ? fmt::format("takes {} arguments, not {}", min, n)
                    : fmt::format("takes {} to {} arguments, not {}", min, max, n));
  }
}

void AptInterpreter::count_point(const ToolpathPoint& p) {
  ++summary_.points;
  if (!summary_.multi_axis && (p.tool_axis - Vector3::UnitZ()).norm() > 1e-9) {
    summary_.multi_axis = true;
  }
}

bool AptInterpreter::interpret(const AptRecord& record, BlockPoints& points) {
  record_ = &record;
  summary_.lines = record.line;
  const std::string& m = record.major;
  if (circle_ && m != "GOTO") {
    if (!circle_used_) {
      fail(fmt::format("comes between the CIRCLE of line {} and its GOTO", circle_line_));
    }
    circle_ = false;
  }
  if (ended_) {
    fail("a record after FINI");
  }
  if (m == "GOTO") return goto_record(points);
  if (m == "FROM") {
    need_args(3, 6);
    Vector3 axis = tool_axis_;
    if (read_axis_arg(3, axis)) tool_axis_ = axis;
    for (int k = 0; k < 3; ++k) position_m_[k] = number(static_cast<std::size_t>(k)) * length_scale();
    position_known_ = true;
  } else if (m == "RAPID") {
    need_args(0, 0);
    rapid_ = true;
  } else if (m == "CIRCLE") {
    circle_record();
  } else if (m == "FEDRAT") {
    feed_record();
  } else if (m == "SPINDL") {
    spindle_record();
  } else if (m == "CUTTER") {
    cutter_record(0);
  } else if (m == "TLDATA") {
    if (record.args.empty() || record.args[0] != "MILL") fail("only TLDATA/MILL (a milling cutter) is read");
    cutter_record(1);
  } else if (m == "LOADTL") {
    tool_record(0);
  } else if (m == "LOAD") {
    if (record.args.empty() || record.args[0] != "TOOL") fail("only LOAD/TOOL,n is read");
    tool_record(1);
  } else if (m == "TLAXIS") {
    need_args(3, 3);
    if (!read_axis_arg(0, tool_axis_)) fail("needs i, j, k");
  } else if (m == "MULTAX") {
    need_args(0, 1);
    if (!record.args.empty() && record.args[0] != "ON" && record.args[0] != "OFF") fail_arg(0, "neither ON nor OFF");
  } else if (m == "UNITS") {
    units_record();
  } else if (m == "FINI") {
    ended_ = true;
  } else if ((m == "CUTCOM" || m == "CYCLE") && record.args.size() == 1 && record.args[0] == "OFF") {
    // Compensation or a cycle switched off: the state deflex assumes.
  } else if (m == "CUTCOM") {
    fail(
        "cutter radius compensation moves the tool off the programmed path by a radius the control holds: export "
        "the cutter's centre path");
  } else if (m == "CYCLE") {
    fail("canned cycles are not read: export the cycle as GOTO moves");
  } else if (!ai_no_effect(m)) {
    fail(fmt::format("not a CL record deflex reads (it reads {})", kAptRecordsRead));
  }
  return false;
}

bool AptInterpreter::read_axis_arg(std::size_t at, Vector3& axis) const {
  if (record_->args.size() < at + 3) return false;
  const Vector3 v(number(at), number(at + 1), number(at + 2));
  const double n = v.norm();
  // CAM writes unit vectors to 6 or 7 decimals; anything else is not a tool axis.
  if (!(std::abs(n - 1.0) <= 1e-3)) {
    fail_arg(at, fmt::format("the tool axis ({}, {}, {}) has length {:.6f}, not 1", number_text(v.x()),
                             number_text(v.y()), number_text(v.z()), n));
  }
  axis = v / n;
  return true;
}

void AptInterpreter::units_record() {
  need_args(1, 1);
  const std::string& u = record_->args[0];
  if (u == "MM") {
    units_ = LengthUnit::kMillimetre;
  } else if (u == "INCHES" || u == "INCH") {
    units_ = LengthUnit::kInch;
  } else {
    fail_arg(0, "neither MM nor INCHES");
  }
  if (!first_point_ && units_ != summary_.units) summary_.units_changed = true;
  if (first_point_) summary_.units = units_;
}

void AptInterpreter::feed_record() {
  need_args(1, 2);
  std::optional<double> value;
  double scale_mm = length_scale() * 1e3;  // per minute in the file's unit
  for (std::size_t i = 0; i < record_->args.size(); ++i) {
    const std::string& a = record_->args[i];
    if (is_number(i)) {
      if (value) fail_arg(i, "a second number");
      value = number(i);
    } else if (a == "MMPM") {
      scale_mm = 1.0;
    } else if (a == "IPM") {
      scale_mm = 25.4;
    } else if (a == "PERMIN") {
    } else if (a == "MMPR" || a == "IPR" || a == "PERREV") {
      fail_arg(i, "a feed per revolution is not read: export the feed per minute (MMPM, IPM)");
    } else {
      fail_arg(i, "not a feed unit deflex reads (MMPM, IPM, PERMIN)");
    }
  }
  if (!value) fail("needs the feed, a number");
  const double mm_per_min = *value * scale_mm;
  if (*value < 0 || mm_per_min > toolpath_limits::kMaxFeedMmPerMin) {
    fail(fmt::format("a feed of {} mm/min is outside 0..{} mm/min", number_text(mm_per_min),
                     number_text(toolpath_limits::kMaxFeedMmPerMin)));
  }
  feed_m_s_ = mm_per_min / 60000.0;
  feed_line_ = record_->line;
}

void AptInterpreter::spindle_record() {
  need_args(1, 3);
  const auto& args = record_->args;
  if (args.size() == 1 && (args[0] == "OFF" || args[0] == "ON")) {
    spindle_ = args[0] == "ON" ? spindle_direction_ : SpindleState::kOff;
    spindle_off_line_ = args[0] == "OFF" ? record_->line : 0;
    return;
  }
  std::optional<double> rpm;
  SpindleState direction = SpindleState::kClockwise;  // ISO 4343: CLW unless told
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (is_number(i)) {
      if (rpm) fail_arg(i, "a second number");
      rpm = number(i);
    } else if (args[i] == "CLW") {
      direction = SpindleState::kClockwise;
    } else if (args[i] == "CCLW") {
      direction = SpindleState::kCounterClockwise;
    } else if (args[i] == "SFM" || args[i] == "SMM") {
      fail_arg(i, "a surface speed is not read: export the spindle speed in RPM");
    } else if (args[i] != "RPM") {
      fail_arg(i, "not a SPINDL word deflex reads (RPM, CLW, CCLW, ON, OFF)");
    }
  }
  if (!rpm) fail("needs the speed, a number (rev/min)");
  if (*rpm < 0 || *rpm > toolpath_limits::kMaxSpindleRpm) {
    fail(fmt::format("a spindle speed outside 0..{} rev/min", number_text(toolpath_limits::kMaxSpindleRpm)));
  }
  spindle_rpm_ = *rpm;
  spindle_ = spindle_direction_ = direction;
  spindle_off_line_ = 0;
}

void AptInterpreter::cutter_record(std::size_t first) {
  need_args(first + 1, first + 7);
  CutterGeometry c;
  c.diameter_m = number(first) * length_scale();
  c.corner_radius_m = record_->args.size() > first + 1 ? number(first + 1) * length_scale() : 0.0;
  c.line = record_->line;
  if (!(c.diameter_m > 0.0) || c.diameter_m > 1.0) {
    fail_arg(first, "a cutter diameter outside 0..1000 mm");
  }
  if (c.corner_radius_m < 0.0 || c.corner_radius_m > 0.5 * c.diameter_m + 1e-9) {
    fail_arg(first + 1, "a corner radius outside 0..half the diameter");
  }
  if (!summary_.cutter || first_point_) {
    summary_.cutter = c;  // the cutter in effect at the first point, else the first stated
  }
  for (ToolEntry& t : summary_.tools) {
    if (t.number == tool_ && tool_ != 0) {
      t.cutter = c;
      return;
    }
  }
  pending_cutter_ = c;
}

void AptInterpreter::tool_record(std::size_t number_at) {
  if (record_->args.size() <= number_at) fail("needs the tool number");
  const double n = number(number_at);
  if (n < 0 || n > 99999 || n != std::floor(n)) fail_arg(number_at, "a tool number is a whole number in 0..99999");
  tool_ = static_cast<int>(n);
  for (ToolEntry& t : summary_.tools) {
    if (t.number == tool_) return;
  }
  if (summary_.tools.size() >= toolpath_limits::kMaxTools) {
    fail(fmt::format("more than {} different tools", toolpath_limits::kMaxTools));
  }
  summary_.tools.push_back({tool_, record_->line, pending_cutter_});
  pending_cutter_.reset();
}

}  // namespace deflex::detail
