// Laser-tracker traces: time-stamped TCP positions, and their CSV form (t_s,x_mm,y_mm,z_mm).
#pragma once

#include <string>
#include <vector>

#include "deflex/model/types.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

/// One tracker reading: time (s) and the measured TCP (reflector) position (m), in the robot base
/// frame or in the tracker's own frame; every trace compared with another must use the same frame.
struct TrackerSample {
  double t_s = 0.0;
  Vector3 p_m = Vector3::Zero();
};

/// A measured (or simulated) path: samples in time order.
using TrackerTrace = std::vector<TrackerSample>;

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

/// Total length of the polyline through the samples (m).
double trace_length_m(const TrackerTrace& trace);

}  // namespace deflex
