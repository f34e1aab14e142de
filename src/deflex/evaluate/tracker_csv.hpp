// Laser-tracker traces as CSV files (t_s,x_mm,y_mm,z_mm): what a tracker exports and deflex reads back,
// and what the simulated cell's tracker writes.
#pragma once

#include <string>

#include "deflex/model/tracker_trace.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

/// Reads a tracker CSV file: a header row with the columns t_s, x_mm, y_mm, z_mm in any order
/// (other columns are ignored), then one sample a row. Positions are converted to m. Throws
/// DataError naming the file, line and column for a missing column, a cell that is not a finite
/// number, time going backwards, or a file with no samples.
TrackerTrace read_tracker_csv(const std::string& path);
/// The same from text in memory; `source` names it in messages.
TrackerTrace parse_tracker_csv(const std::string& text, const std::string& source);

/// Writes t_s,x_mm,y_mm,z_mm (positions in mm, 10 significant digits) into an output of the caller's
/// transaction (output_file.hpp). Throws OutputError when a write fails.
void write_tracker_csv(const TrackerTrace& trace, OutputFile& out);
/// The same into a file of its own.
void write_tracker_csv(const TrackerTrace& trace, const std::string& path);

}  // namespace deflex
