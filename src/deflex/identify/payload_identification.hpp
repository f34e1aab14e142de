// Identification of the end effector's mass, centre of gravity and the sensor bias from static poses
// (the usual least-squares formulation). At rest, in the sensor frame, with g_s = sensor_R_base g:
//   f = m g_s + b_f                           linear in (m, b_f)
//   t = c x (m g_s) + b_t = -[g_s]x (m c) + b_t  linear in (m c, b_t)
#pragma once

#include <string>
#include <vector>

#include "deflex/model/robot_model.hpp"

namespace deflex {

struct PayloadObservation {
  Matrix3 base_R_sensor = Matrix3::Identity();
  Vector6 wrench_sensor = Vector6::Zero();  ///< decoupled reading at rest, sensor frame, N and Nm
};

struct PayloadEstimate {
  double mass_kg = 0.0;
  Vector3 cog_sensor_m = Vector3::Zero();  ///< zero when moments are not measured
  Vector6 bias_sensor = Vector6::Zero();
  bool moments_used = false;
  double force_residual_rms_N = 0.0;
  double moment_residual_rms_Nm = 0.0;
  double force_condition_number = 0.0;  ///< of the force regressor; large = poses too alike
  double moment_condition_number = 0.0;
  int poses = 0;
};

/// Least squares over the poses. `use_moments`: also identify the centre of gravity and moment bias
/// (6-component sensors). Throws InputError with fewer than 3 poses, non-finite data, orientations
/// that do not excite every unknown (condition number above 1e8), or a mass that comes out negative.
[[nodiscard]] PayloadEstimate identify_payload(const std::vector<PayloadObservation>& poses, bool use_moments,
                                               const Vector3& gravity_base_m_s2 = Vector3(0.0, 0.0, -9.81));

/// Reads static poses from CSV (`fx_N,fy_N,fz_N`, optional `mx_Nm,my_Nm,mz_Nm`; the orientation as
/// `qw,qx,qy,qz` (base_R_sensor quaternion) or as joints `q1_deg..qN_deg`, which need `model` and
/// flange_T_sensor). Raw readings: `crosstalk` is applied to them. Throws DataError naming file:line.
[[nodiscard]] std::vector<PayloadObservation> read_payload_observations(const std::string& csv_path,
                                                                        const RobotModel* model,
                                                                        const Pose& flange_T_sensor,
                                                                        const Matrix6& crosstalk, bool& has_moments);

}  // namespace deflex
