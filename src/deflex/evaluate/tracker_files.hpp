// Tracker files as a measurement session leaves them: Spatial Analyzer (SA) ASCII point exports and
// plain CSV with the unit in the header, read into one form (named, optionally time-stamped points in
// the file's own frame, in m), and the SA form written back.
//
// SA exports points "always in the working coordinate frame" with a choice of name columns
// (Collection Group Target, Group Target, Target or none), Cartesian, cylindrical or spherical
// coordinates, optional tolerances, uncertainties and time stamps, space or comma separators, fixed or
// scientific notation, and optional `//` comment lines naming the SA version, the working frame and the
// coordinate system (SA User Manual, "Exporting ASCII Formatted Points"). What the reader takes from
// the comments, and how a file without them is read, is in docs/evaluation.md ("Tracker files").
#pragma once

#include <string>
#include <vector>

#include "deflex/model/tracker_trace.hpp"
#include "deflex/model/types.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

/// One measured point: its name (empty when the file has none), its time stamp (s, NaN when the file
/// has none) and its position (m) in the file's frame; `line` is the file's line (1-based).
struct TrackerPoint {
  std::string name;
  double t_s = kNaN;
  Vector3 p_m = Vector3::Zero();
  int line = 0;
};

/// The points of one file and what its header said.
struct TrackerFile {
  std::string source;       ///< the path, for messages
  std::string format;       ///< "sa" or "csv"
  std::string frame;        ///< the working frame the header names ("" when it names none)
  std::string version;      ///< the SA version line's text ("" when absent)
  std::string coordinates;  ///< "cartesian", "cylindrical" or "spherical"
  std::string length_unit;  ///< "mm", "m", "cm", "in" or "ft": where it came from is in `unit_from`
  std::string unit_from;    ///< "header", "option" or "column names"
  /// "utf-8", or "windows-1252" for a file that is not UTF-8 (SA's ANSI export on Windows): its text
  /// (the frame, the point names) is then converted to UTF-8 as it is read, so a frame named "Cafè"
  /// compares equal in both encodings.
  std::string encoding = "utf-8";
  bool has_time = false;
  bool has_names = false;
  std::vector<TrackerPoint> points;
};

/// How to read a file whose header leaves something out. Nothing is ever guessed: a length unit that
/// neither the header nor `length_unit` gives is an error, and so is a disagreement between them.
struct TrackerReadOptions {
  std::string length_unit;  ///< "mm", "m", "cm", "in", "ft" ("" = from the header)
  std::string angle_unit;   ///< "deg" or "rad" for cylindrical and spherical files ("" = from the header)
  /// The SA file's columns, space or comma separated, e.g. "target x y z time" (see
  /// docs/evaluation.md for the names); "" = from the header's `// Columns:` comment, else only the
  /// one layout that cannot be mistaken: up to three text names, then x y z.
  std::string columns;
  std::string expect_frame;  ///< when set, a header naming another working frame is an error
};

/// Reads an SA ASCII export or a plain CSV (`t_s` optional, `x_mm,y_mm,z_mm` or `x_m,y_m,z_m`; other
/// columns ignored, text or numbers), telling them apart by their first line. Throws DataError naming
/// the file and line: no length unit, mixed coordinate systems, a frame other than `expect_frame`, a
/// line with another layout than the file's, a value that is not a finite number, a coordinate beyond
/// +-100 m, an unknown column name, a file without points, in a CSV positions in two units or a time
/// stamp before the previous one.
TrackerFile read_tracker_file(const std::string& path, const TrackerReadOptions& options = {});
/// The same from text in memory; `source` names it in messages.
TrackerFile parse_tracker_file(const std::string& text, const std::string& source,
                               const TrackerReadOptions& options = {});

/// The points as a trace for time-based work (time alignment, the time-synchronous error): every point
/// must have a time stamp and the stamps must increase strictly. Throws DataError naming the file and
/// line of the first point without a stamp, a repeated stamp or a stamp that goes back; `what` says
/// what asked for the times.
TrackerTrace timed_trace(const TrackerFile& file, const std::string& what);
/// The points as a trace for distance-only work: time stamps kept when present (0 otherwise), order
/// as in the file.
TrackerTrace untimed_trace(const TrackerFile& file);

/// How write_sa_export writes.
struct SaExportOptions {
  std::string frame = "Robot Base";  ///< the working frame named in the header
  std::string collection = "deflex";
  std::string group = "trace";
  bool comma = false;       ///< comma separated instead of spaces
  bool scientific = false;  ///< full-precision scientific notation instead of 6 decimals of a mm
  bool time = true;         ///< a time column (s)
};
/// Writes `trace` as an SA ASCII export: comment lines naming the version, working frame, units
/// (millimetres) and columns, then "Collection Group Target X Y Z [Time]" a point, targets named
/// P000001, P000002 ... Throws InputError, before writing, for names read_tracker_file would not read
/// back as given (a frame with a line break or blanks at its ends, a collection or group that is
/// empty or holds a blank, a comma or a control character), OutputError when a write fails.
void write_sa_export(const TrackerTrace& trace, OutputFile& out, const SaExportOptions& options = {});
void write_sa_export(const TrackerTrace& trace, const std::string& path, const SaExportOptions& options = {});

}  // namespace deflex
