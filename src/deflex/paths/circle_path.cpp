// Sampling of circular TCP paths.
#include "deflex/paths/circle_path.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/paths/pose_source.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

void circle_frame(const CirclePath& circle, Vector3& u, Vector3& v) {
  if (!circle.normal.allFinite() || circle.normal.norm() < 1e-12) {
    throw InputError("circle: the plane normal must be a finite, non-zero vector");
  }
  const Vector3 n = circle.normal.normalized();
  if (!circle.start_reference.allFinite()) {
    throw InputError("circle: the start reference direction is not finite");
  }
  const Vector3 in_plane = circle.start_reference - circle.start_reference.dot(n) * n;
  // Relative test: a reference nearly along the normal gives a start direction dominated by
  // rounding, so the start point would be arbitrary.
  if (in_plane.norm() < 1e-6 * std::max(1.0, circle.start_reference.norm())) {
    throw InputError("circle: the start reference direction is parallel to the normal; choose another");
  }
  u = in_plane.normalized();
  v = n.cross(u);
}

Vector3 circle_point(const CirclePath& circle, double angle_rad) {
  if (!std::isfinite(angle_rad)) {
    throw InputError("circle point: the angle is not a finite number");
  }
  if (!circle.centre_m.allFinite() || !std::isfinite(circle.radius_m)) {
    throw InputError("circle point: the circle's centre and radius must be finite");
  }
  Vector3 u, v;
  circle_frame(circle, u, v);
  return circle.centre_m + circle.radius_m * (std::cos(angle_rad) * u + std::sin(angle_rad) * v);
}

Eigen::Quaterniond checked_unit_quaternion(const Eigen::Quaterniond& q, const char* what, double tolerance) {
  if (!q.coeffs().allFinite()) {
    throw InputError(fmt::format("{}: quaternion is not finite", what));
  }
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > tolerance) {
    throw InputError(fmt::format("{}: not a unit quaternion (norm {:.9f})", what, norm));
  }
  return q.normalized();
}

std::vector<Pose> sample_circle(const CirclePath& circle, const Eigen::Quaterniond& tcp_orientation) {
  CirclePoseSource source(circle, tcp_orientation);
  check_held_path_points(*source.size() - 1);
  std::vector<Pose> poses;
  poses.reserve(*source.size());
  for (Pose p; source.next(p);) {
    poses.push_back(p);
  }
  return poses;
}

}  // namespace deflex
