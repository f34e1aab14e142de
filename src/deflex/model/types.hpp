// Vocabulary types shared by all of deflex. SI units throughout: m, rad, N, Nm, s.
#pragma once

#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace deflex {

/// Largest number of joints a serial chain may have. Joint-sized vectors and matrices use this as
/// their maximum size, so they live on the stack and never allocate, whatever the robot's size.
inline constexpr int kMaxJoints = 7;

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Pose = Eigen::Isometry3d;

/// Joint values (rad), joint deflections (rad) or joint torques (Nm), one entry a joint.
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxJoints, 1>;
/// n x n joint-space matrix (stiffness, Nm/rad).
using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxJoints, kMaxJoints>;
/// 6 x n geometric Jacobian: rows 0-2 linear velocity (m/s per rad/s), rows 3-5 angular velocity,
/// both in the robot base frame.
using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxJoints>;

/// Wrench [Fx Fy Fz Mx My Mz] in N and Nm. Unless a name says otherwise it is expressed in the
/// robot base frame, with the moment taken about the wrench application point (WAP).
using Wrench = Vector6;

/// Small twist-like displacement [dx dy dz drx dry drz] in m and rad, in the robot base frame.
using Displacement = Vector6;

/// A circle's geometry alone, in the robot base frame (m): what a force model placed on a circle needs
/// of it (the sampled path, paths/circle_path.hpp, converts to it).
struct CircleGeometry {
  Vector3 centre_m = Vector3::Zero();
  double radius_m = 0.1;
  Vector3 normal = Vector3::UnitZ();  ///< need not be unit; must not be zero
};

inline constexpr double kPi = 3.14159265358979323846;
/// A quiet NaN: "no value" in a field that has none (a skipped row, an unmeasured figure).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double deg_to_rad(double deg) { return deg * kPi / 180.0; }
inline constexpr double rad_to_deg(double rad) { return rad * 180.0 / kPi; }

}  // namespace deflex
