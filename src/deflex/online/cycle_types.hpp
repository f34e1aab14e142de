// What one online compensation cycle takes and gives (its configuration, input, output and status),
// on their own so that what drives or records a cycle (the controller links, the session report)
// does not include the compensator. SI units (rad, m, N, Nm, s).
#pragma once

#include <cstdint>

#include "deflex/model/types.hpp"

namespace deflex {

/// KDL's sign convention: >= 0 the output is usable (positive: degraded), < 0 nothing to send.
enum class CycleStatus : int {
  kOk = 0,
  kNoForceYet = 1,     ///< no valid force sample since start: correction zero
  kStaleForce = 2,     ///< watchdog expired: correction ramping to zero
  kForceFault = 3,     ///< a fault sample was seen within fault_hold_s: correction ramping to zero
  kHeld = 4,           ///< the caller asked to hold (hold_to_zero): correction ramping to zero
  kInvalidInput = -1,  ///< wrong joint count or non-finite joints/time: q_command must not be sent
  /// A joint of q_planned, q_feedback or the compensated command outside the robot's limits (by more
  /// than kCycleLimitToleranceRad): q_command must not be sent.
  kOutsideLimits = -2,
};

/// How far beyond a joint limit a cycle's joints may be (rounding of a controller's feedback), rad.
inline constexpr double kCycleLimitToleranceRad = 1e-6;

[[nodiscard]] const char* to_string(CycleStatus s);

/// Where the Jacobian of dtheta = K^-1 J(q)^T W is evaluated.
enum class JacobianAt {
  kPlanned,   ///< q_planned: the configuration the command is for (the exact compensation form of
              ///< compliance.hpp, compensated_configuration)
  kFeedback,  ///< q_feedback: the configuration the arm has now (the paper's "current pose")
};

struct OnlineConfig {
  double period_s = 0.004;                  ///< nominal cycle (4 ms EGM; 0.1 s like the paper)
  double max_joint_correction_rad = 0.01;   ///< per joint |dtheta_i| bound
  double max_tcp_correction_m = 0.005;      ///< bound on |J_p dtheta| (TCP translation)
  double max_correction_rate_rad_s = 0.05;  ///< per joint |d(dtheta_i)/dt| bound, also the ramp to zero
  /// Bound on the rate of the correction's TCP translation |J_p d(dtheta)/dt| (m/s): the ramp of a
  /// correction that is a TCP offset (EGM path correction), and at the TCP for every link.
  double max_tcp_rate_m_s = 0.005;
  double watchdog_s = 0.05;   ///< no valid force sample for this long: ramp to zero
  double fault_hold_s = 0.5;  ///< after a fault sample, hold the correction target at zero
  JacobianAt jacobian_at = JacobianAt::kPlanned;

  /// Throws InputError on a non-positive or non-finite value.
  void validate() const;
};

struct CycleInput {
  double t_s = 0.0;        ///< cycle time (s), monotonic (the caller's clock)
  JointVector q_planned;   ///< rad: the configuration the command is for (a nominal the caller holds)
  JointVector q_feedback;  ///< rad: where the arm is; the sensor orientation comes from it
  /// Added to the conditioned wrench before the model (base frame, at the WAP): the hybrid strategy
  /// subtracts its force model's wrench here, the predictive one adds the model's change.
  Wrench wrench_offset_base = Wrench::Zero();
  /// > 0: the conditioned wrench is extrapolated this far ahead (s) along its recent slope (the
  /// predictive strategy without a force model).
  double wrench_lead_s = 0.0;
  /// The caller cannot trust this cycle's wrench (its strategy could not evaluate its model): the
  /// correction ramps to zero as on a stale force.
  bool hold_to_zero = false;
};

struct CycleOutput {
  JointVector q_command;                         ///< q_planned - dtheta, rad
  JointVector dtheta;                            ///< applied correction (after bounds), rad
  Wrench wrench_base = Wrench::Zero();           ///< wrench the model used (base frame, at the WAP)
  Wrench wrench_measured_base = Wrench::Zero();  ///< conditioned measurement, before offset and lead
  CycleStatus status = CycleStatus::kNoForceYet;
  bool size_limited = false;      ///< the joint or TCP bound cut the correction
  bool rate_limited = false;      ///< a rate bound (joint or TCP) cut the change of correction
  double tcp_correction_m = 0.0;  ///< |J_p dtheta|, m
  Vector3 tcp_deflection_base_m =
      Vector3::Zero();       ///< J_p dtheta (base frame, m): the TCP offset the correction cancels
  double force_age_s = 0.0;  ///< time since the last valid force sample
  int samples_used = 0;      ///< force samples conditioned during this cycle
};

struct CompensatorCounters {
  std::uint64_t cycles = 0, invalid_inputs = 0;
  std::uint64_t samples_ok = 0, samples_fault = 0, samples_invalid = 0, samples_dropped = 0;
};

}  // namespace deflex
