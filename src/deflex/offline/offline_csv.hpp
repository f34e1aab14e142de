// CSV output of an offline compensation: desired and compensated joints and poses, the wrench and
// the predicted deflection and residual per point. mm, degrees and mrad at this edge; every column
// names its unit.
#pragma once

#include <string>
#include <vector>

#include "deflex/offline/compensate_path.hpp"

namespace deflex {

/// The header row write_offline_csv() writes for a robot of `dof` joints.
[[nodiscard]] std::vector<std::string> offline_csv_columns(int dof);

/// Writes one row per point (0-based `index` column), after the header a '#' comment naming the
/// robot and the force model. Throws Error when the file cannot be written.
void write_offline_csv(const OfflineResult& result, const std::string& path);

}  // namespace deflex
