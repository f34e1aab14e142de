// The online compensation cycle (paper, Figure 3): every cycle the latest conditioned wrench and a
// configuration give dtheta = K^-1 J^T W by the lumped model, bounded in size and rate; stale or
// faulty force data ramp the correction to zero. What the correction is added to is the caller's
// business: a controller link subtracts it from the nominal it holds itself (never from what the
// controller echoes back). step() never allocates, locks or throws (tests prove it with
// AllocationGuard).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "deflex/model/frame_cache.hpp"
#include "deflex/online/cycle_types.hpp"
#include "deflex/online/force_pipeline.hpp"

namespace deflex {

/// Thread safety: one thread at a time: push_force(), drain() and step() on the loop's thread (a
/// sensor driver on a thread of its own hands its samples over through ForceHandoff).
class OnlineCompensator {
 public:
  /// Throws ModelError when the model has no stiffness, InputError on a bad configuration.
  OnlineCompensator(const RobotModel& model, const SensorConfig& sensor, const OnlineConfig& config);
  // Not copied: its frames refer to its own copy of the model.
  OnlineCompensator(const OnlineCompensator&) = delete;
  OnlineCompensator& operator=(const OnlineCompensator&) = delete;

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
  /// The frames of this cycle's configurations (the feedback, the target), computed once each: the
  /// strategy and the link ask here too, so the cycle runs forward kinematics at most twice.
  [[nodiscard]] FrameCache& frames() { return frames_; }
  [[nodiscard]] const OnlineConfig& config() const { return config_; }
  [[nodiscard]] const ForcePipeline& pipeline() const { return pipeline_; }

 private:
  RobotModel model_;  // a copy: the compensator may outlive the caller's model
  OnlineConfig config_;
  Pose flange_T_sensor_;
  ForcePipeline pipeline_;
  FrameCache frames_;  // the cycle's frames, shared with the strategy and the link (one FK a configuration)
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
  // The cycle's stages (step()).
  bool refuse(const CycleInput& in, CycleOutput& out) noexcept;
  void condition_queued(const Matrix3& base_R_sensor, double t_s, CycleOutput& out) noexcept;
  JointVector target_correction(const CycleInput& in, const Wrench& used, const Workspace*& ws,
                                CycleOutput& out) noexcept;
  void approach(const JointVector& target, double dt, CycleOutput& out) noexcept;
  double last_force_t_s_ = 0.0;
  double last_fault_t_s_ = -1e300;
  double last_cycle_t_s_ = 0.0;
  bool have_cycle_ = false;
  CompensatorCounters counters_;
};

}  // namespace deflex
