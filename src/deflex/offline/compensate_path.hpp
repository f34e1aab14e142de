// Offline compensation of a planned path (paper, Figure 2): the process wrench expected at each
// point, the deflection the lumped joint-compliance model predicts, and the command that makes the
// deflected arm end where the task wants it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "deflex/force/force_model.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/paths/path_ik.hpp"

namespace deflex {

/// One compensated path point. Joint values in rad, poses and displacements in the base frame (m,
/// rad), wrench in N and Nm.
struct OfflinePoint {
  JointVector q_desired;                   ///< from the path's inverse kinematics
  JointVector q_command;                   ///< compensated command, exact form: q_desired - K^-1 J_wap(q_desired)^T W
  Pose tcp_desired;                        ///< the pose the task wants (the path's pose)
  Pose tcp_command;                        ///< FK(q_command): the equivalent compensated Cartesian target
  ArmConfiguration configuration_command;  ///< confdata of q_command (for robtargets)
  /// The wrench the model uses: base frame, moment about the robot's wrench application point
  /// (the force model's moment about the TCP, moved to the WAP when the two differ).
  Wrench wrench_base;
  /// Uncompensated: the TCP displacement when the loaded arm is commanded to q_desired, from
  /// FK(q_desired) to FK(q_actual), q_actual solving q = q_desired + K^-1 J_wap(q)^T W (the core's
  /// deflected_configuration, not the first-order J dtheta). [m; rad].
  Displacement predicted_deflection = Displacement::Zero();
  /// After compensation: from tcp_desired to FK(deflected_configuration(q_command, W)). Zero up to
  /// the IK and fixed-point tolerances when the model is the robot; a check of the exact form.
  Displacement predicted_residual = Displacement::Zero();
};

struct OfflineResult {
  std::vector<OfflinePoint> points;  ///< empty when the path was streamed (PathCompensator)
  std::size_t point_count = 0;       ///< points compensated
  double max_deflection_m = 0.0;     ///< largest |translation| of predicted_deflection
  double mean_deflection_m = 0.0;    ///< mean |translation| of predicted_deflection over all points
  double max_deflection_rad = 0.0;
  double max_residual_m = 0.0;  ///< largest |translation| of predicted_residual
  double max_residual_rad = 0.0;
  double max_correction_m = 0.0;          ///< largest |p_command - p_desired|
  double max_joint_correction_rad = 0.0;  ///< largest |q_command - q_desired| over joints and points
  std::string robot_name;
  std::string stiffness_note;
  std::string force_description;
  bool predicted = true;  ///< false when OfflineOptions::predict was off (deflection figures unset)
};

struct OfflineOptions {
  /// Predict the uncompensated deflection and the residual (two fixed-point solves and FKs a
  /// point). Off, only the compensation itself runs (q_command, tcp_command, wrench).
  bool predict = true;
};

/// Compensates every point of `path` (joint values from solve_path_ik) whose desired poses are
/// `tcp_poses`, under the wrench `force` predicts at each point. Throws InputError, in Release too,
/// when the sizes disagree, the force model has data for a different number of points, the robot has
/// no joint stiffness, a point's joints or desired pose are not finite, a compensated joint leaves its
/// limits, or the deflection does not converge (a load far beyond the model's range); each names the
/// path point (0-based).
[[nodiscard]] OfflineResult compensate_path(const RobotModel& model, const JointPath& path,
                                            const std::vector<Pose>& tcp_poses, const ForceModel& force,
                                            const OfflineOptions& options);
[[nodiscard]] OfflineResult compensate_path(const RobotModel& model, const JointPath& path,
                                            const std::vector<Pose>& tcp_poses, const ForceModel& force);
/// The same into `out`, whose point buffer is reused: once it has held a path as long, compensating
/// another allocates nothing and touches no fresh page (100,000 points are 55 MB of results). For a
/// caller that compensates path after path. On an error `out` is left empty (its buffer kept).
void compensate_path(const RobotModel& model, const JointPath& path, const std::vector<Pose>& tcp_poses,
                     const ForceModel& force, const OfflineOptions& options, OfflineResult& out);

/// The same a point at a time, for paths too long to hold: compensate() gives exactly the point
/// compensate_path gives, throws the same errors, and keeps only the summary (max, mean), so memory
/// does not grow with the path.
/// Ownership (docs/architecture.md): the compensator copies the model, so one returned from the
/// function that built the model stays valid; the force model (polymorphic, often large: a table) it
/// shares when given as a shared pointer, else it keeps a reference that must outlive it, and a
/// temporary force model does not compile.
/// Thread safety: one thread at a time (its own Workspace and running summary); compensators on
/// different threads may share the force model.
class PathCompensator {
 public:
  /// Throws InputError when the robot has no joint stiffness.
  PathCompensator(const RobotModel& model, const ForceModel& force, const OfflineOptions& options = {});
  /// The same, sharing the force model; InputError when it is null.
  PathCompensator(const RobotModel& model, std::shared_ptr<const ForceModel> force, const OfflineOptions& options = {});
  PathCompensator(const RobotModel& model, ForceModel&& force, const OfflineOptions& options = {}) = delete;
  /// Compensates path point `index` (0-based, in order) with joints `q_desired` and pose `tcp_desired`.
  /// The reference stays valid until the next call.
  const OfflinePoint& compensate(std::size_t index, const JointVector& q_desired, const Pose& tcp_desired);
  /// The figures over the points so far (`points` left empty). Throws InputError when no point was
  /// compensated or a force table's length differs from the path's.
  [[nodiscard]] OfflineResult summary() const;

 private:
  RobotModel model_;
  std::shared_ptr<const ForceModel> force_owner_;  // null when the caller keeps the force model
  const ForceModel& force_;
  OfflineOptions options_;
  Workspace ws_;
  JointVector q_actual_;
  JointVector dtheta_desired_;  // K^-1 J(q_desired)^T W, rad: the compensation, and where the arm nearly goes
  JointVector q_start_;
  OfflinePoint point_;
  OfflineResult result_;
  double sum_deflection_ = 0.0;
  std::size_t count_ = 0;
};

}  // namespace deflex
