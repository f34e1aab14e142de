// Sampling of straight TCP paths.
#include "deflex/paths/line_path.hpp"

#include <fmt/format.h>

#include "deflex/model/errors.hpp"
#include "deflex/paths/circle_path.hpp"

namespace deflex {

std::vector<Pose> sample_line(const LinePath& line, const Eigen::Quaterniond& tcp_orientation) {
  if (line.points < 2) {
    throw InputError(fmt::format("line: needs at least 2 points (got {})", line.points));
  }
  if (!line.start_m.allFinite() || !line.end_m.allFinite()) {
    throw InputError("line: start and end must be finite");
  }
  if ((line.end_m - line.start_m).norm() < 1e-9) {
    throw InputError("line: start and end coincide");
  }
  const Eigen::Quaterniond orientation = checked_unit_quaternion(tcp_orientation, "line: TCP orientation");
  std::vector<Pose> poses;
  poses.reserve(static_cast<std::size_t>(line.points));
  for (int i = 0; i < line.points; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(line.points - 1);
    Pose p = Pose::Identity();
    p.linear() = orientation.toRotationMatrix();
    p.translation() = (1.0 - s) * line.start_m + s * line.end_m;
    poses.push_back(p);
  }
  return poses;
}

}  // namespace deflex
