// Sampling of straight TCP paths.
#include "deflex/paths/line_path.hpp"

#include <fmt/format.h>

#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/pose_source.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

std::vector<Pose> sample_line(const LinePath& line, const Eigen::Quaterniond& tcp_orientation) {
  LinePoseSource source(line, tcp_orientation);
  check_held_path_points(*source.size() - 1);
  std::vector<Pose> poses;
  poses.reserve(*source.size());
  for (Pose p; source.next(p);) {
    poses.push_back(p);
  }
  return poses;
}

}  // namespace deflex
