// Reading a CAM toolpath: G-code (gcode_reader.hpp) or APT/CL data (apt_reader.hpp), chosen by the
// file's extension, streamed a point at a time (a file of millions of lines costs one read buffer
// and one block's state) or read whole into a vector. docs/machining.md lists what is read and what
// is refused.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "deflex/toolpath/toolpath_options.hpp"
#include "deflex/toolpath/toolpath_point.hpp"

namespace deflex {

/// A toolpath read a point at a time.
/// Thread safety: one thread at a time (next() reads the file on).
class ToolpathReader {
 public:
  virtual ~ToolpathReader() = default;
  ToolpathReader(const ToolpathReader&) = delete;
  ToolpathReader& operator=(const ToolpathReader&) = delete;

  /// The next point, in program order; false after the last. Throws DataError "FILE:LINE: word 'W':
  /// ..." for anything the reader refuses (docs/machining.md), and "FILE: ..." at the end of a program
  /// that gave no point.
  virtual bool next(ToolpathPoint& out) = 0;
  /// What the reader has seen so far; complete once next() has returned false.
  [[nodiscard]] virtual const ToolpathSummary& summary() const = 0;

 protected:
  ToolpathReader() = default;
};

/// The format of a toolpath file from its extension (any case): .nc .gcode .tap G-code, .apt .cls APT/CL
/// data. Throws InputError naming the file and listing the extensions for any other.
[[nodiscard]] ToolpathFormat toolpath_format_for(const std::string& path);

/// Opens a toolpath file by its extension (toolpath_format_for). Throws InputError for an unknown
/// extension or options out of range, DataError when the file cannot be read (input_file.hpp).
[[nodiscard]] std::unique_ptr<ToolpathReader> open_toolpath(const std::string& path,
                                                            const ToolpathOptions& options = {});

/// A whole toolpath in memory.
struct Toolpath {
  ToolpathSummary summary;
  std::vector<ToolpathPoint> points;
};

/// The most points read_toolpath() holds: beyond them, stream with open_toolpath().
inline constexpr std::size_t kMaxHeldToolpathPoints = 10'000'000;

/// Reads a whole toolpath file (open_toolpath's rules). Throws DataError beyond kMaxHeldToolpathPoints.
[[nodiscard]] Toolpath read_toolpath(const std::string& path, const ToolpathOptions& options = {});

/// Reads every point of `reader` (the same limit).
[[nodiscard]] Toolpath read_toolpath(ToolpathReader& reader);

}  // namespace deflex
