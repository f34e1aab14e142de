// One compliance-calibration observation (a load applied, the TCP displacement measured) and the
// CSV file format that holds them. Format reference: docs/identify.md.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/model/types.hpp"

namespace deflex {

/// One loaded-minus-unloaded observation at one configuration. SI units, robot base frame.
struct StiffnessMeasurement {
  JointVector q;                    ///< configuration (the joint encoders' reading), rad
  Wrench wrench_base;               ///< applied wrench [N; Nm], base frame, moment about the WAP
  Vector3 dp_m;                     ///< TCP (measured point) displacement, loaded minus unloaded, m
  std::optional<Vector3> drot_rad;  ///< orientation change (rotation vector), rad, where measured
  double weight = 1.0;              ///< relative weight (inverse variance ratio), > 0
  int line = 0;                     ///< line of the source file (0: not from a file), for messages
};

/// Reads the measurement CSV. Columns are found by name, in any order:
///   q1_deg..qN_deg (or qJ_rad), fx_N, fy_N, fz_N, mx_Nm, my_Nm, mz_Nm, dx_mm, dy_mm, dz_mm (or _m),
///   optional drx_rad, dry_rad, drz_rad (all three or none), optional weight.
/// N is the number of consecutive qJ columns. Other columns (a planner's x_mm, notes) are ignored.
/// Throws DataError naming the file, line and column: missing columns, NaN/empty cells (by
/// CsvTable), weights <= 0, joint values beyond +-720 deg, displacements beyond 100 mm (a unit
/// mistake, not an elastic deflection), a file without data rows.
std::vector<StiffnessMeasurement> read_stiffness_measurements(const std::string& csv_path);

/// Writes measurements in the same layout (deg, N, Nm, mm; drx.. only if every row has them).
/// Throws Error when the file cannot be written.
void write_stiffness_measurements(const std::string& csv_path, const std::vector<StiffnessMeasurement>& data,
                                  const std::vector<std::string>& comments = {});

}  // namespace deflex
