// The online compensation cycle (paper, Figure 3): every cycle the latest conditioned wrench and a
// configuration give dtheta = K^-1 J^T W by the lumped model, bounded in size and rate; stale or
// faulty force data ramp the correction to zero. What the correction is added to is the caller's
// business: a controller link subtracts it from the nominal it holds itself (never from what the
// controller echoes back). step() never allocates, locks or throws (tests prove it with
// AllocationGuard).
#pragma once

#include <array>
#include <vector>
#include <cstdint>

#include "deflex/model/kinematics.hpp"
#include "deflex/online/force_pipeline.hpp"

namespace deflex {

/// Where the Jacobian of dtheta = K^-1 J(q)^T W is evaluated.
enum class JacobianAt {
  kPlanned,   ///< q_planned: the configuration the command is for (the exact compensation form of
              ///< compliance.hpp, compensated_configuration)
  kFeedback,  ///< q_feedback: the configuration the arm has now (the paper's "current pose")
};

struct OnlineConfig {
  double period_s = 0.004;                    ///< nominal cycle (4 ms EGM; 0.1 s like the paper)
  double max_joint_correction_rad = 0.01;     ///< per joint |dtheta_i| bound
  double max_tcp_correction_m = 0.005;        ///< bound on |J_p dtheta| (TCP translation)
  double max_correction_rate_rad_s = 0.05;    ///< per joint |d(dtheta_i)/dt| bound, also the ramp to zero
  /// Bound on the rate of the correction's TCP translation |J_p d(dtheta)/dt| (m/s): the ramp of a
  /// correction that is a TCP offset (EGM path correction), and at the TCP for every link.
  double max_tcp_rate_m_s = 0.005;
  double watchdog_s = 0.05;                   ///< no valid force sample for this long: ramp to zero
  double fault_hold_s = 0.5;                  ///< after a fault sample, hold the correction target at zero
  JacobianAt jacobian_at = JacobianAt::kPlanned;

  /// Throws InputError on a non-positive or non-finite value.
  void validate() const;
};

/// KDL's sign convention: >= 0 the output is usable (positive: degraded), < 0 nothing to send.
enum class CycleStatus : int {
  kOk = 0,
  kNoForceYet = 1,    ///< no valid force sample since start: correction zero
  kStaleForce = 2,    ///< watchdog expired: correction ramping to zero
  kForceFault = 3,    ///< a fault sample was seen within fault_hold_s: correction ramping to zero
  kHeld = 4,          ///< the caller asked to hold (hold_to_zero): correction ramping to zero
  kInvalidInput = -1, ///< wrong joint count or non-finite joints/time: q_command must not be sent
};

[[nodiscard]] const char* to_string(CycleStatus s);

struct CycleInput {
  double t_s = 0.0;         ///< cycle time (s), monotonic (the caller's clock)
  JointVector q_planned;    ///< rad: the configuration the command is for (a nominal the caller holds)
  JointVector q_feedback;   ///< rad: where the arm is; the sensor orientation comes from it
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
  JointVector q_command;                ///< q_planned - dtheta, rad
  JointVector dtheta;                   ///< applied correction (after bounds), rad
  Wrench wrench_base = Wrench::Zero();  ///< wrench the model used (base frame, at the WAP)
  Wrench wrench_measured_base = Wrench::Zero();  ///< conditioned measurement, before offset and lead
  CycleStatus status = CycleStatus::kNoForceYet;
  bool size_limited = false;            ///< the joint or TCP bound cut the correction
  bool rate_limited = false;            ///< a rate bound (joint or TCP) cut the change of correction
  double tcp_correction_m = 0.0;        ///< |J_p dtheta|, m
  Vector3 tcp_deflection_base_m = Vector3::Zero();  ///< J_p dtheta (base frame, m): the TCP offset the correction cancels
  double force_age_s = 0.0;             ///< time since the last valid force sample
  int samples_used = 0;                 ///< force samples conditioned during this cycle
};

struct CompensatorCounters {
  std::uint64_t cycles = 0, invalid_inputs = 0;
  std::uint64_t samples_ok = 0, samples_fault = 0, samples_invalid = 0, samples_dropped = 0;
};

class OnlineCompensator {
 public:
  /// Throws ModelError when the model has no stiffness, InputError on a bad configuration.
  OnlineCompensator(const RobotModel& model, const SensorConfig& sensor, const OnlineConfig& config);

  /// Queues one raw sample (conditioned at the next step() with that cycle's orientation). The queue
  /// holds two cycles of samples at the sensor's rate (at least 64), sized at construction; a full
  /// queue drops the oldest sample and counts it. Never allocates.
  void push_force(const ForceSample& sample) noexcept;
  /// Pulls every new sample of `source` into the queue.
  void drain(ForceSource& source) noexcept;

  /// One cycle. Never allocates, locks or throws.
  CycleOutput step(const CycleInput& input) noexcept;
  /// step() after drain(source).
  CycleOutput step(const CycleInput& input, ForceSource& source) noexcept;

  /// Back to the start state: zero correction, empty queue, filter unprimed (controller restart).
  void reset() noexcept;

  /// DC group delay of the force low-pass, s (the conditioned wrench lags the sensor by this much).
  [[nodiscard]] double filter_delay_s() const { return filter_delay_s_; }
  /// Slope of the conditioned wrench over the last `slope_window_s` (per s, base frame at the WAP).
  [[nodiscard]] const Wrench& wrench_slope() const { return slope_; }

  [[nodiscard]] const CompensatorCounters& counters() const { return counters_; }
  /// Samples the queue holds before push_force() drops the oldest, and the samples it holds now.
  [[nodiscard]] int queue_capacity() const { return queue_capacity_; }
  [[nodiscard]] int queued() const { return queue_count_; }
  [[nodiscard]] const RobotModel& model() const { return model_; }
  [[nodiscard]] const OnlineConfig& config() const { return config_; }
  [[nodiscard]] const ForcePipeline& pipeline() const { return pipeline_; }

 private:
  RobotModel model_;  // a copy: the compensator may outlive the caller's model
  OnlineConfig config_;
  Pose flange_T_sensor_;
  ForcePipeline pipeline_;
  Workspace ws_;
  Jacobian jac_;

  // Sized once from the sample rate and the cycle period: at the paper's 100 ms cycle a 1 kHz DAQ
  // delivers 100 samples a cycle, and every one must reach the filter.
  std::vector<ForceSample> queue_;
  int queue_capacity_ = 0;
  int queue_head_ = 0, queue_count_ = 0;

  JointVector correction_;
  bool have_force_ = false;
  Wrench wrench_base_ = Wrench::Zero();
  double filter_delay_s_ = 0.0;

  // Conditioned wrench at recent cycles, for its slope (fixed ring, no allocation).
  static constexpr int kSlopeRing = 32;
  static constexpr double kSlopeWindowS = 0.05;
  std::array<double, kSlopeRing> slope_t_{};
  std::array<Wrench, kSlopeRing> slope_w_{};
  int slope_head_ = 0, slope_count_ = 0;
  Wrench slope_ = Wrench::Zero();
  void update_slope(double t_s) noexcept;
  double last_force_t_s_ = 0.0;
  double last_fault_t_s_ = -1e300;
  double last_cycle_t_s_ = 0.0;
  bool have_cycle_ = false;
  CompensatorCounters counters_;
};

}  // namespace deflex
