// CSV output of an offline compensation: desired and compensated joints and poses, the wrench and
// the predicted deflection and residual per point. mm, degrees and mrad at this edge; every column
// names its unit.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "deflex/offline/compensate_path.hpp"
#include "deflex/text/csv_table.hpp"

namespace deflex {

/// The header row write_offline_csv() writes for a robot of `dof` joints.
[[nodiscard]] std::vector<std::string> offline_csv_columns(int dof);

/// Writes one row per point (0-based `index` column), after the header a '#' comment naming the
/// robot and the force model, into a file of its own (output_file.hpp: it appears whole or not at
/// all). Throws InputError for a path that cannot be written, OutputError when a write fails.
void write_offline_csv(const OfflineResult& result, const std::string& path);

/// The same file a point at a time (deflex offline streams long paths through it): the rows are
/// byte for byte those write_offline_csv writes, into an output of the caller's transaction.
/// Thread safety: one thread at a time.
class OfflineCsvWriter {
 public:
  OfflineCsvWriter(OutputFile& out, int dof, const std::string& robot_name, const std::string& force_description,
                   bool predicted);
  /// With `extra_columns` after the standard ones (a toolpath's feed, spindle, engagement, spin, ...):
  /// write() then takes one value for each. `note` goes at the end of the '#' line.
  OfflineCsvWriter(OutputFile& out, int dof, const std::string& robot_name, const std::string& force_description,
                   bool predicted, const std::vector<std::string>& extra_columns, const std::string& note);
  void write(std::size_t index, const OfflinePoint& point, std::span<const double> extra = {});
  /// Flushes the rows to the output; throws OutputError when a write failed.
  void finish();

 private:
  int dof_;
  std::size_t extra_;
  CsvWriter out_;
  std::vector<double> row_;
  Eigen::Quaterniond q_desired_ = Eigen::Quaterniond::Identity();  // sign continuity along the path
  bool have_quaternion_ = false;
};

}  // namespace deflex
