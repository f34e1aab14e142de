// The compensated G-code program: the source program again, with every point of its motion blocks
// moved to where the caller's compensation puts it. A line that is not a motion is copied byte for
// byte; a motion line keeps its words, order and number format, with new X Y Z values (all three,
// absolute: G90 is written where the source ran under G91); an arc (and a line the reader split,
// ToolpathOptions::max_linear_step_m) is written as the G1 chords that were compensated, the first on
// the source line, the others on lines of their own. Tool-axis words are written as programmed (3-axis
// G-code cannot say an orientation; the robot program carries it). docs/machining.md.
#pragma once

#include <memory>
#include <string>

#include "deflex/text/output_file.hpp"
#include "deflex/toolpath/toolpath_options.hpp"
#include "deflex/toolpath/toolpath_point.hpp"

namespace deflex {

/// Streams: memory does not grow with the program. Nothing appears at the output until finish()
/// (text/output_file.hpp); destroyed unfinished, nothing is written.
/// Thread safety: one thread at a time.
class GcodeWriteBack {
 public:
  /// Reads `source_path` again (with the options it was read with) and writes `output_path`, which
  /// must not be the source (InputError, whatever the spelling or link). `what` names the output in
  /// messages.
  GcodeWriteBack(const std::string& source_path, const std::string& output_path, const ToolpathOptions& options = {},
                 const std::string& what = "compensated program");
  /// Into `output`, one output of a transaction: finish() writes it whole, the transaction commits.
  GcodeWriteBack(const std::string& source_path, OutputFile& output, const ToolpathOptions& options = {});
  ~GcodeWriteBack();
  GcodeWriteBack(const GcodeWriteBack&) = delete;
  GcodeWriteBack& operator=(const GcodeWriteBack&) = delete;

  /// The next point of the program, as GcodeReader gave it (same file, same options, same order),
  /// and where it goes: `compensated_position_m`, workpiece frame. Throws InputError when the point
  /// is not the program's next point (another file, other options, a point left out) or the
  /// position is not finite or beyond 100 m; DataError for the program itself (as GcodeReader).
  void add(const ToolpathPoint& point, const Vector3& compensated_position_m);
  /// Writes the rest of the program and commits (a file of its own). Throws InputError when the
  /// program has points that were not given.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace deflex
