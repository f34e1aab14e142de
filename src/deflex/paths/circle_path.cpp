// Sampling of circular TCP paths.
#include "deflex/paths/circle_path.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

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
  if (!std::isfinite(circle.radius_m) || circle.radius_m <= 0.0) {
    throw InputError(fmt::format("circle: radius must be positive and finite (got {} m)", circle.radius_m));
  }
  if (!circle.centre_m.allFinite() || !std::isfinite(circle.start_angle_rad)) {
    throw InputError("circle: centre and start angle must be finite");
  }
  if (circle.points < 3) {
    throw InputError(fmt::format("circle: needs at least 3 points (got {})", circle.points));
  }
  const Eigen::Quaterniond orientation = checked_unit_quaternion(tcp_orientation, "circle: TCP orientation");
  Vector3 u, v;
  circle_frame(circle, u, v);
  const double sign = circle.clockwise ? -1.0 : 1.0;
  const double step = 2.0 * kPi / static_cast<double>(circle.points - 1);
  std::vector<Pose> poses;
  poses.reserve(static_cast<std::size_t>(circle.points));
  for (int i = 0; i < circle.points; ++i) {
    // The last point is set to the first exactly (not by rounding of cos/sin at 2 pi), so a closed
    // path really closes.
    const double angle = circle.start_angle_rad + sign * step * static_cast<double>(i % (circle.points - 1));
    Pose p = Pose::Identity();
    p.linear() = orientation.toRotationMatrix();
    p.translation() = circle.centre_m + circle.radius_m * (std::cos(angle) * u + std::sin(angle) * v);
    poses.push_back(p);
  }
  return poses;
}

}  // namespace deflex
