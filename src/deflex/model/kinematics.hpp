// Forward kinematics and the geometric Jacobian of a serial chain. All functions run on a
// preallocated Workspace and never allocate.
#pragma once

#include <array>

#include "deflex/model/robot_model.hpp"

namespace deflex {

/// Per-call scratch for one RobotModel (Pinocchio's Model/Data split). Create one per thread;
/// it holds the results of the last forward_kinematics() call.
/// Thread safety: one thread at a time (forward_kinematics() writes it, and the algorithms built on
/// it read what it wrote): each thread its own.
struct Workspace {
  explicit Workspace(const RobotModel& model);

  int dof = 0;
  JointVector q;                                  ///< configuration of the last FK call, rad
  std::array<Vector3, kMaxJoints> axis_base{};    ///< joint axes in the base frame (unit)
  std::array<Vector3, kMaxJoints> origin_base{};  ///< a point on each joint axis, base frame, m
  Pose base_T_flange = Pose::Identity();
  Pose base_T_tcp = Pose::Identity();
  Pose base_T_wap = Pose::Identity();
  Jacobian jacobian;  ///< scratch for algorithms built on FK
};

/// Computes every joint frame and the flange, TCP and WAP poses at q (rad), in the robot base
/// frame. Throws InputError, in Release too, when q does not have one value a joint, or the workspace
/// was made for another robot (a cold branch: the real-time cycle checks its inputs before, and gives
/// a status, so it never reaches it). Finite values are the callers' to check at the edge.
void forward_kinematics(const RobotModel& model, Workspace& ws, const JointVector& q);

/// Geometric Jacobian of the point `point_base` (m, base frame) rigidly attached to the last link,
/// using the frames of the last forward_kinematics() call. Linear rows first.
void point_jacobian(const Workspace& ws, const Vector3& point_base, Jacobian& J);

/// Which point of the end effector a Jacobian or a deflection refers to.
enum class EndPoint { kFlange, kTcp, kWap };

/// Pose of the chosen end point after the last forward_kinematics() call.
[[nodiscard]] const Pose& end_pose(const Workspace& ws, EndPoint point);

/// FK then the Jacobian of the chosen end point, in one call.
void jacobian(const RobotModel& model, Workspace& ws, const JointVector& q, EndPoint point, Jacobian& J);

/// Pose of the TCP in the robot base frame at q (convenience; same as FK then ws.base_T_tcp).
[[nodiscard]] Pose tcp_pose(const RobotModel& model, Workspace& ws, const JointVector& q);

/// Small rigid displacement between two poses: [p_b - p_a; rotation vector of R_b R_a^T], base frame.
[[nodiscard]] Displacement pose_difference(const Pose& a, const Pose& b);

/// Applies a small base-frame displacement [dp; drot] to a pose (exact rotation via angle-axis).
[[nodiscard]] Pose apply_displacement(const Pose& pose, const Displacement& d);

/// The same wrench [F; M] (base frame) with its moment taken about another point: M_to = M_from +
/// (p_from - p_to) x F, points in the base frame (m). Force models give the moment about the TCP,
/// the compliance model takes it about the WAP. Never allocates.
[[nodiscard]] inline Wrench moment_moved(const Wrench& w, const Vector3& from_m, const Vector3& to_m) {
  Wrench out = w;
  out.tail<3>() += (from_m - to_m).cross(Vector3(w.head<3>()));
  return out;
}

}  // namespace deflex
