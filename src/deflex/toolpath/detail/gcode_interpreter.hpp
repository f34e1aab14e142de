// The G-code machine: modal state carried from block to block, each line's words given their
// meaning, and each motion block turned into its points (BlockPoints). GcodeReader and the
// write-back both run it over the same lines, so they agree on every point.
#pragma once

#include <array>
#include <string>

#include "deflex/toolpath/detail/block_points.hpp"
#include "deflex/toolpath/detail/gcode_words.hpp"
#include "deflex/toolpath/detail/line_reader.hpp"
#include "deflex/toolpath/toolpath_options.hpp"

namespace deflex::detail {

/// How a block states the tool axis.
enum class OrientationForm {
  kNone,    ///< not at all (the axis carried from before)
  kAngles,  ///< A B C rotary angles (degrees)
  kVector,  ///< a direction vector: A3= B3= C3= (Siemens TRAORI) or I J K on G0/G1 (Fanuc G43.5)
};

/// What the write-back needs to know of the last motion block interpreted.
struct GcodeBlockFacts {
  int motion_g = 0;  ///< 0, 1, 2, 3
  bool incremental = false;
  LengthUnit units = LengthUnit::kMillimetre;
  OrientationForm orientation = OrientationForm::kNone;
  bool vector_by_ijk = false;               ///< the vector form is I J K (else A3= B3= C3=)
  Vector3 abc_start_deg = Vector3::Zero();  ///< the angle form's rotary angles at the start
  Vector3 abc_end_deg = Vector3::Zero();    ///< and at the end
  bool orientation_changes = false;         ///< the tool axis turns along the block
};

/// A block's words sorted by meaning (pointers into the line's GcodeLine).
struct GcodeBlockWords {
  const GcodeWord* axis[3] = {};    // X Y Z
  const GcodeWord* rotary[3] = {};  // A B C
  const GcodeWord* vector[3] = {};  // A3= B3= C3=
  const GcodeWord* offset[3] = {};  // I J K
  const GcodeWord* r = nullptr;
  const GcodeWord* f = nullptr;
  const GcodeWord* s = nullptr;
  const GcodeWord* t = nullptr;
  const GcodeWord* p = nullptr;
  const GcodeWord* h = nullptr;
  const GcodeWord* d = nullptr;
  // G words by modal group, as codes times ten (G43.4: 434).
  const GcodeWord* g_motion = nullptr;
  const GcodeWord* g_plane = nullptr;
  const GcodeWord* g_units = nullptr;
  const GcodeWord* g_distance = nullptr;
  const GcodeWord* g_arc_distance = nullptr;
  const GcodeWord* g_feed_mode = nullptr;
  const GcodeWord* g_comp = nullptr;
  const GcodeWord* g_length = nullptr;
  const GcodeWord* g_offset = nullptr;
  const GcodeWord* g_path = nullptr;
  const GcodeWord* g_dwell = nullptr;
  const GcodeWord* m_spindle = nullptr;
  const GcodeWord* m_tool_change = nullptr;
  const GcodeWord* m_stop = nullptr;
  const GcodeWord* m_end = nullptr;
  const GcodeWord* m_coolant = nullptr;
};

/// Thread safety: one thread at a time.
class GcodeInterpreter {
 public:
  GcodeInterpreter(std::string source, const ToolpathOptions& options);

  /// Interprets one line. True when it is a motion block with points, which `points` then gives.
  /// Throws DataError "SOURCE:LINE: word 'W': ..." for anything refused.
  bool interpret(const SourceLine& line, BlockPoints& points);

  /// The last line's words.
  [[nodiscard]] const GcodeLine& words() const { return words_; }
  /// Facts of the last block for which interpret() returned true.
  [[nodiscard]] const GcodeBlockFacts& facts() const { return facts_; }
  [[nodiscard]] ToolpathSummary& summary() { return summary_; }
  [[nodiscard]] const ToolpathSummary& summary() const { return summary_; }

  /// Notes a point given out (the summary's count and multi-axis flag).
  void count_point(const ToolpathPoint& p);

 private:
  using Block = GcodeBlockWords;

  void classify(Block& b) const;
  void classify_g(const GcodeWord& w, Block& b) const;
  void classify_m(const GcodeWord& w, Block& b) const;
  void apply_settings(const Block& b);
  void apply_spindle_and_tool(const Block& b);
  void apply_modes(const Block& b);
  void apply_keywords();
  bool plan_motion(const Block& b, BlockPoints& points);
  [[nodiscard]] Vector3 block_target(const Block& b, std::array<bool, 3>& known_after) const;
  [[nodiscard]] PointContext point_context() const;
  void orientation_end(const Block& b, bool linear, AxisPath& path, Vector3& abc_end_deg);
  void check_cutting(const Block& b, int motion) const;
  void plan_arc(const Block& b, int motion, const Vector3& target, const PointContext& context, const AxisPath& axis,
                BlockPoints& points);
  std::size_t block_count(double count, const std::string& what) const;
  void add_tool(int number);
  [[noreturn]] void fail(const GcodeWord* w, const std::string& what) const;
  [[noreturn]] void fail_text(const std::string& what) const;
  [[noreturn]] void fail_word(std::string_view word, const std::string& what) const;
  [[nodiscard]] const GcodeWord* first_moving_word(const Block& b) const;
  [[nodiscard]] double length_scale() const;

  std::string source_;
  ToolpathOptions options_;
  SourceLine line_;
  GcodeLine words_;
  GcodeBlockFacts facts_;
  ToolpathSummary summary_;

  // Modal state.
  int motion_ = -1;  // 0..3; -1: none yet, or cancelled by G80
  ArcPlane plane_ = ArcPlane::kXy;
  LengthUnit units_ = LengthUnit::kMillimetre;
  bool incremental_ = false;
  bool arc_centre_absolute_ = false;
  double feed_m_s_ = 0.0;
  std::size_t feed_line_ = 0;
  double spindle_rpm_ = 0.0;
  std::size_t spindle_rpm_line_ = 0;
  SpindleState spindle_ = SpindleState::kOff;
  std::size_t spindle_off_line_ = 0;  // the M5 that stopped it; 0: never started
  int selected_tool_ = 0;
  int active_tool_ = 0;
  Vector3 position_m_ = Vector3::Zero();
  std::array<bool, 3> known_{false, false, false};
  Vector3 tool_axis_ = Vector3::UnitZ();
  OrientationForm axis_form_ = OrientationForm::kNone;
  Vector3 abc_deg_ = Vector3::Zero();
  bool tcp_vector_ = false;  // Fanuc G43.5
  bool traori_ = false;      // Siemens TRAORI
  int work_offset_ = 0;
  std::size_t work_offset_line_ = 0;
  std::size_t end_line_ = 0;  // M2/M30
  std::uint64_t segments_ = 0;
  bool first_point_ = true;
};

}  // namespace deflex::detail
