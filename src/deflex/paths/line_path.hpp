// A straight TCP path sampled into base-frame poses with the orientation held.
#pragma once

#include <vector>

#include "deflex/model/types.hpp"

namespace deflex {

/// A straight segment in the robot base frame, m. Both ends are sampled.
struct LinePath {
  Vector3 start_m = Vector3::Zero();
  Vector3 end_m = Vector3::Zero();
  int points = 2;  ///< >= 2; evenly spaced, first = start, last = end
};

/// Samples the segment into base_T_tcp poses with `tcp_orientation` (a unit quaternion within 1e-6).
/// Throws InputError on fewer than 2 points, non-finite ends, zero length or a non-unit quaternion.
[[nodiscard]] std::vector<Pose> sample_line(const LinePath& line, const Eigen::Quaterniond& tcp_orientation);

}  // namespace deflex
