// APT / CL data (ISO 4343 records as NX, CATIA, Fusion and SprutCAM export them): source lines joined
// into records ('$' continues a line, "$$" starts a comment), each record given its meaning, GOTOs
// and CIRCLE arcs turned into points.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "deflex/toolpath/detail/block_points.hpp"
#include "deflex/toolpath/detail/line_reader.hpp"
#include "deflex/toolpath/toolpath_options.hpp"

namespace deflex::detail {

/// One CL record: "MAJOR/arg,arg,..." or a bare major word ("RAPID", "FINI").
struct AptRecord {
  std::string major;              ///< upper case, blanks collapsed ("GOTO", "TOOL PATH", "END-OF-PATH")
  std::vector<std::string> args;  ///< trimmed; upper case outside text records
  std::string text;               ///< the rest of a text record (PARTNO, PPRINT), as written
  std::size_t line = 0;           ///< its first line
};

/// Joins lines into records. Thread safety: one thread at a time.
class AptRecordReader {
 public:
  explicit AptRecordReader(LineReader& lines) : lines_(lines) {}
  /// The next record; false at the end. Throws DataError for a continuation at the end of the file, a
  /// record of more than 64 KiB, an empty argument.
  bool next(AptRecord& out);

 private:
  LineReader& lines_;
  std::string joined_;
};

/// Thread safety: one thread at a time.
class AptInterpreter {
 public:
  AptInterpreter(std::string source, const ToolpathOptions& options);
  /// Interprets one record; true when it gives points (then in `points`). Throws DataError
  /// "SOURCE:LINE: record 'MAJOR': ...".
  bool interpret(const AptRecord& record, BlockPoints& points);
  /// End-of-file checks (a CIRCLE waiting for its GOTO).
  void finish();
  void count_point(const ToolpathPoint& p);
  [[nodiscard]] const ToolpathSummary& summary() const { return summary_; }

 private:
  bool goto_record(BlockPoints& points);
  void circle_record();
  void feed_record();
  void spindle_record();
  void cutter_record(std::size_t first);
  void tool_record(std::size_t number_at);
  void units_record();
  [[nodiscard]] bool read_axis_arg(std::size_t at, Vector3& axis) const;
  [[nodiscard]] double number(std::size_t i) const;
  [[nodiscard]] bool is_number(std::size_t i) const;
  void need_args(std::size_t min, std::size_t max) const;
  void check_cutting() const;
  [[noreturn]] void fail(const std::string& what) const;
  [[noreturn]] void fail_arg(std::size_t i, const std::string& what) const;
  [[nodiscard]] double length_scale() const { return units_ == LengthUnit::kInch ? 0.0254 : 1e-3; }

  std::string source_;
  ToolpathOptions options_;
  const AptRecord* record_ = nullptr;
  ToolpathSummary summary_;

  LengthUnit units_;
  double feed_m_s_ = 0.0;
  std::size_t feed_line_ = 0;
  double spindle_rpm_ = 0.0;
  SpindleState spindle_ = SpindleState::kOff;
  SpindleState spindle_direction_ = SpindleState::kClockwise;  // what SPINDL/ON restarts
  std::size_t spindle_off_line_ = 0;
  int tool_ = 0;
  std::optional<CutterGeometry> pending_cutter_;  // stated before the tool it belongs to is loaded
  bool rapid_ = false;                            // RAPID: the next GOTO only
  bool circle_ = false;                           // a CIRCLE waits for its GOTOs
  bool circle_used_ = false;
  std::size_t circle_line_ = 0;
  Vector3 circle_centre_m_ = Vector3::Zero();
  Vector3 circle_axis_ = Vector3::UnitZ();
  double circle_radius_m_ = 0.0;
  Vector3 position_m_ = Vector3::Zero();
  bool position_known_ = false;
  Vector3 tool_axis_ = Vector3::UnitZ();
  bool ended_ = false;
  std::uint64_t segments_ = 0;
  bool first_point_ = true;
};

}  // namespace deflex::detail
