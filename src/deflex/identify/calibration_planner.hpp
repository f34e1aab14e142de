// Planning a compliance-calibration experiment: which poses to put the arm in and which loads to
// apply there so that every joint's compliance is observable from TCP position measurements, in
// the region of the workspace where the task runs (the paper's local calibration).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "deflex/model/robot_model.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

struct CalibrationPlanOptions {
  Vector3 region_min_m = Vector3(1.2, -0.5, 0.6);  ///< box of TCP positions, robot base frame, m
  Vector3 region_max_m = Vector3(1.8, 0.5, 1.4);
  double load_n = 500.0;   ///< magnitude of the applied force, N
  int poses = 12;          ///< number of distinct poses in the plan
  int loads_per_pose = 2;  ///< loads applied (one after the other) at each pose
  /// The force is applied at a point this far from the WAP, perpendicular to the tool's z axis
  /// (a calibration bar on the tool), so it also twists the wrist; 0: forces at the WAP only.
  double lever_m = 0.25;
  /// TCP orientation in the base frame; default: tool z axis pointing down (rotation of 180 deg
  /// about the base y axis).
  Eigen::Quaterniond orientation = Eigen::Quaterniond(0.0, 0.0, 1.0, 0.0);
  /// Candidate turns of the tool about its own z axis, rad.
  std::vector<double> spin_rad = {0.0, kPi / 2, kPi, 3 * kPi / 2};
  int grid_per_axis = 4;   ///< candidate positions per axis of the region
  double noise_m = 10e-6;  ///< tracker noise per axis, m, for the predicted standard errors
};

/// One row of the plan: go to q, apply `wrench_base` (the force at `load_point_base`), measure.
struct CalibrationPoint {
  int pose = 0;             ///< 1-based pose number (several loads share a pose)
  JointVector q;            ///< rad
  Pose base_T_tcp;          ///< the TCP pose at q
  Wrench wrench_base;       ///< at the WAP, base frame, N and Nm
  Vector3 load_point_base;  ///< where the force acts, base frame, m
  Vector3 expected_dp_m;    ///< first-order deflection with the robot file's stiffness, m
};

struct CalibrationPlan {
  std::vector<CalibrationPoint> points;
  /// Smallest singular value of the regressor with each column scaled by the file's compliance:
  /// a change of every compliance by the fraction e moves the TCPs by at least e * this, in m.
  double min_singular_value_m = 0.0;
  /// Condition number of the regressor with columns scaled to unit norm (as identify reports it).
  double condition_number = 0.0;
  /// se(c_j)/c_j predicted for `noise_m` (the same as se(k_j)/k_j to first order).
  std::vector<double> predicted_relative_std_error;
  int candidate_poses = 0;  ///< grid points x spins tried
  int reachable_poses = 0;  ///< of those, reachable inside the joint limits and not near singular
  std::vector<std::string> warnings;
};

/// Chooses poses and loads greedily: each step adds the (pose, load) that most increases the
/// smallest eigenvalue of the nominal-compliance-scaled information matrix A^T A (a maximin,
/// "E-optimal" design); while A^T A is still singular the largest log-determinant gain decides.
/// Requires a robot with stiffness (the nominal values set the column scaling). Throws InputError
/// for a bad region or options, and when no pose of the region is reachable.
[[nodiscard]] CalibrationPlan plan_calibration(const RobotModel& model, const CalibrationPlanOptions& options);

/// Writes the plan as CSV for the cell operator (docs/identify.md): pose, q1_deg.., x_mm..,
/// qw..qz, fx_N..mz_Nm, load_x_mm.., expected_dx_mm..; the plan figures as comment lines.
void write_calibration_plan(OutputFile& out, const CalibrationPlan& plan,
                            const std::vector<std::string>& comments = {});
/// The same into a file of its own (output_file.hpp).
void write_calibration_plan(const std::string& path, const CalibrationPlan& plan,
                            const std::vector<std::string>& comments = {});

}  // namespace deflex
