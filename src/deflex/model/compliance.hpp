// Salisbury's lumped joint-compliance model (paper, section 2.2): diagonal joint stiffness K,
// rigid links. For a wrench W at the wrench application point (WAP), in the robot base frame:
//
//   dtheta = K^-1 J_wap(theta)^T W          joint deflection, rad
//   dx     = J_tcp(theta) dtheta            TCP deflection (first order), m and rad
//   C      = J_wap K^-1 J_wap^T             6x6 Cartesian compliance at the WAP
//
// Which configuration theta each function evaluates J at is said on each function: the elastic
// deflection really happens at the configuration the arm takes, theta_actual = theta_cmd + dtheta.
// None of these functions allocates.
#pragma once

#include "deflex/model/kinematics.hpp"

namespace deflex {

struct ComplianceOptions {
  /// Include the complementary stiffness K_c = d(J^T W)/dtheta (large loads): the linearised
  /// equilibrium becomes (K - K_c) dtheta = J^T W. Off by default, as in the paper.
  bool complementary_stiffness = false;
};

/// Joint deflection dtheta (rad) under wrench W (N, Nm; base frame, moment about the WAP) with J
/// evaluated at q itself: the form for a configuration the arm actually takes (online use, and the
/// exact form for compensation). Runs FK at q. Throws ModelError, in Release too, when the robot has
/// no stiffness (a bare URDF), and InputError as forward_kinematics() does; every call below that
/// deflects (and cartesian_compliance) goes through it.
void joint_deflection(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                      JointVector& dtheta, const ComplianceOptions& options = {});

/// First-order TCP deflection [m; rad] at q under W: J_tcp(q) dtheta, dtheta from joint_deflection().
[[nodiscard]] Displacement tcp_deflection(const RobotModel& model, Workspace& ws, const JointVector& q,
                                          const Wrench& wrench_base, const ComplianceOptions& options = {});
/// The same, also giving the joint deflection dtheta (rad) it is made of: one FK for both (the
/// batch calls of the Python module use it).
[[nodiscard]] Displacement tcp_deflection(const RobotModel& model, Workspace& ws, const JointVector& q,
                                          const Wrench& wrench_base, JointVector& dtheta,
                                          const ComplianceOptions& options = {});

/// 6x6 Cartesian compliance at the WAP, C = J K^-1 J^T at q: [m/N, m/Nm; rad/N, rad/Nm].
[[nodiscard]] Matrix6 cartesian_compliance(const RobotModel& model, Workspace& ws, const JointVector& q);

/// Complementary stiffness K_c(q, W) = d(J_wap(q)^T W)/dq (n x n, Nm/rad), with the wrench held
/// fixed in the base frame and applied at the WAP as it moves. Analytic.
void complementary_stiffness(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                             JointMatrix& Kc);

/// Compensated command for a known wrench (exact form): the arm, commanded to q_cmd, deflects to
/// q_cmd + K^-1 J(q_actual)^T W; asking q_actual = q_desired gives
///   q_cmd = q_desired - K^-1 J_wap(q_desired)^T W,
/// with J evaluated at q_desired. Exact for the lumped model; no iteration.
void compensated_configuration(const RobotModel& model, Workspace& ws, const JointVector& q_desired,
                               const Wrench& wrench_base, JointVector& q_cmd);
/// The same, also giving the joint deflection dtheta = K^-1 J_wap(q_desired)^T W (rad) it subtracted:
/// where the arm commanded to q_desired goes first (the offline prediction starts there).
void compensated_configuration(const RobotModel& model, Workspace& ws, const JointVector& q_desired,
                               const Wrench& wrench_base, JointVector& q_cmd, JointVector& dtheta);

enum class DeflectionStatus : int {
  kConverged = 0,
  kNotConverged = -1,  ///< fixed-point iteration did not settle (load far too large for the model)
};

/// The configuration the arm takes when commanded to q_cmd under W (the "forward" problem):
/// solves q = q_cmd + K^-1 J_wap(q)^T W by fixed-point iteration (contracts quickly at realistic
/// loads: the correction is ~1e-3 rad). Stops when the step is below tol_rad.
DeflectionStatus deflected_configuration(const RobotModel& model, Workspace& ws, const JointVector& q_cmd,
                                         const Wrench& wrench_base, JointVector& q_actual, double tol_rad = 1e-13,
                                         int max_iterations = 50);

/// The same fixed point, iterated from `q_start` instead of q_cmd: a caller that knows where the
/// arm will nearly be (q_cmd + K^-1 J(q_cmd)^T W, or the configuration the command was computed for)
/// saves the iterations that would only get there. The answer is the same fixed point to tol_rad;
/// the step test still certifies it, so a poor start costs iterations, never accuracy.
DeflectionStatus deflected_configuration_from(const RobotModel& model, Workspace& ws, const JointVector& q_cmd,
                                              const Wrench& wrench_base, const JointVector& q_start,
                                              JointVector& q_actual, double tol_rad = 1e-13, int max_iterations = 50);

}  // namespace deflex
