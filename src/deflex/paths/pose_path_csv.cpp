// CSV reader for TCP pose paths.
#include "deflex/paths/detail/pose_path_csv.hpp"

#include "deflex/paths/pose_source.hpp"

namespace deflex {
namespace {

std::vector<Pose> drain(PoseSource& source) {
  std::vector<Pose> poses;
  for (Pose p; source.next(p);) {
    check_held_path_points(poses.size());
    poses.push_back(p);
  }
  return poses;
}

}  // namespace

std::vector<Pose> read_pose_path_csv(const std::string& path) {
  PoseCsvSource source(path);
  return drain(source);
}

std::vector<Pose> parse_pose_path_csv(const std::string& text, const std::string& source) {
  PoseCsvSource poses(text, source);
  return drain(poses);
}

}  // namespace deflex
