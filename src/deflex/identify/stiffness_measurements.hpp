// One compliance-calibration observation (a load applied, the TCP displacement measured) and the
// CSV file format that holds them. Format reference: docs/identify.md.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "deflex/model/types.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

class CsvReader;

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

/// The same file a row at a time (deflex identify streams a million rows through it): next() gives
/// the measurements read_stiffness_measurements gives, with the same errors.
/// Thread safety: one thread at a time (next() reads the file on).
class StiffnessMeasurementReader {
 public:
  /// Opens the file and checks its columns; throws DataError as read_stiffness_measurements does.
  explicit StiffnessMeasurementReader(const std::string& csv_path);
  ~StiffnessMeasurementReader();
  StiffnessMeasurementReader(const StiffnessMeasurementReader&) = delete;
  StiffnessMeasurementReader& operator=(const StiffnessMeasurementReader&) = delete;
  /// The next measurement; false after the last. Throws DataError for a bad row, and for a file
  /// without any data row.
  bool next(StiffnessMeasurement& out);
  /// Number of joint columns (q1..qN).
  [[nodiscard]] int joints() const;
  [[nodiscard]] const std::string& source() const;

  struct UnitColumn {
    std::string name;
    std::size_t index = 0;
    double to_si = 1.0;
  };

 private:
  std::unique_ptr<CsvReader> reader_;
  std::vector<UnitColumn> q_cols_, d_cols_;
  std::vector<std::size_t> wrench_cols_, rot_cols_;
  std::optional<std::size_t> weight_col_;
  std::size_t rows_ = 0;
};

/// Writes measurements in the same layout (deg, N, Nm, mm; drx.. only if every row has them) into an
/// output of the caller's transaction (output_file.hpp). Throws OutputError when a write fails.
void write_stiffness_measurements(OutputFile& out, const std::vector<StiffnessMeasurement>& data,
                                  const std::vector<std::string>& comments = {});
/// The same into a file of its own.
void write_stiffness_measurements(const std::string& csv_path, const std::vector<StiffnessMeasurement>& data,
                                  const std::vector<std::string>& comments = {});

}  // namespace deflex
