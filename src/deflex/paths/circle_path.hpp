// A circular TCP path (the paper's case study: a circle discretised in 81 configurations, under 5
// degrees apart), sampled into base-frame TCP poses with the orientation held.
#pragma once

#include <vector>

#include "deflex/model/types.hpp"

namespace deflex {

/// A circle in the robot base frame, SI units.
///
/// The start point lies at `start_angle_rad` from the start direction u, measured about `normal`
/// (right hand). u is `start_reference` projected into the circle's plane, so with the default
/// normal +z and reference +x the circle starts at centre + radius * x. Counter-clockwise means a
/// positive rotation about `normal` (counter-clockwise seen from the tip of the normal looking down
/// on the plane); `clockwise` reverses it.
struct CirclePath {
  Vector3 centre_m = Vector3::Zero();
  double radius_m = 0.1;
  Vector3 normal = Vector3::UnitZ();  ///< need not be unit; must not be zero
  double start_angle_rad = 0.0;
  bool clockwise = false;
  /// Number of sampled poses. The circle is closed: the last pose repeats the first, so the step
  /// is 360 deg / (points - 1); the paper's 81 points give 4.5 deg steps.
  int points = 81;
  Vector3 start_reference = Vector3::UnitX();  ///< must not be parallel to `normal`

  /// The circle's centre, radius and normal (what force specs place on it, force/force_spec.hpp).
  operator CircleGeometry() const { return {centre_m, radius_m, normal}; }  // NOLINT(google-explicit-constructor)
};

/// The unit start direction u and the in-plane direction v = normal x u of a circle (base frame).
/// Throws InputError when the normal is zero or the reference is parallel to it.
void circle_frame(const CirclePath& circle, Vector3& u, Vector3& v);

/// Point of the circle at the angle `angle_rad` from the start direction (before start_angle is
/// applied and regardless of direction), base frame, m. Throws InputError for an angle, centre or
/// radius that is not finite, and as circle_frame does.
[[nodiscard]] Vector3 circle_point(const CirclePath& circle, double angle_rad);

/// Samples the circle into base_T_tcp poses, all with `tcp_orientation` (normalised; it must be a
/// unit quaternion within 1e-6). The last pose repeats the first. Throws InputError on a
/// non-positive or non-finite radius, fewer than 3 points, a zero normal, a non-finite centre, or a
/// non-unit orientation.
[[nodiscard]] std::vector<Pose> sample_circle(const CirclePath& circle, const Eigen::Quaterniond& tcp_orientation);

/// Checks that a quaternion given by a user is a unit quaternion (within `tolerance`) and returns it
/// normalised. `what` names it in the error (InputError).
[[nodiscard]] Eigen::Quaterniond checked_unit_quaternion(const Eigen::Quaterniond& q, const char* what,
                                                         double tolerance = 1e-6);

}  // namespace deflex
