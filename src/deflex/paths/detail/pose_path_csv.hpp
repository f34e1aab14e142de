// Reading a TCP path from CSV: one pose a row, position in mm and orientation as a unit quaternion,
// both in the robot base frame (columns x_mm,y_mm,z_mm,qw,qx,qy,qz, any order).
#pragma once

#include <string>
#include <vector>

#include "deflex/model/types.hpp"

namespace deflex {

/// The most points a path may have (a circle or line spec, a path CSV): deflex offline streams a
/// path to CSV in constant memory, so this bounds the run time (about 10 min at 6 us a point), not
/// the memory.
inline constexpr int kMaxPathPoints = 100'000'000;

/// Reads base_T_tcp poses (converted to m). Throws DataError naming the file, line and column on a
/// missing column, a non-numeric cell, a quaternion whose norm is off 1 by more than 1e-3 (a typo,
/// not rounding), or a file without rows.
[[nodiscard]] std::vector<Pose> read_pose_path_csv(const std::string& path);

/// Same, from text (`source` names it in errors).
[[nodiscard]] std::vector<Pose> parse_pose_path_csv(const std::string& text, const std::string& source);

}  // namespace deflex
