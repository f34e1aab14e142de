// A correction made smooth enough for a controller that checks what it is sent: FANUC's Stream Motion
// computes each joint's velocity, acceleration and jerk from successive commands and stops the stream
// at the first over its limits (a 0.001 deg step from rest at 8 ms is already ~2000 deg/s^3 of jerk).
// The correction first moves by at most `step` a cycle (a rate limit), then through two moving
// averages of N cycles in cascade. With y the output and s the step:
//     |dy| <= s,   |d2y| <= 2 s / N,   |d3y| <= 4 s / N^2        (first, second, third differences)
// so velocity <= s/T, acceleration <= 2s/(N T^2), jerk <= 4s/(N^2 T^3) at a cycle of T, whatever the
// correction asked for. N is the smallest that meets the limits (taps_for()).
//
// Why this and not a time-optimal jerk-limited tracker: every output is a weighted mean of earlier
// rate-limited values, so it never leaves their range (no overshoot, and a correction within the
// bound of the nominal stays within it), the bounds are closed forms a test can hold it to, and a
// cycle is a fixed amount of arithmetic. Its price is a delay of N - 1 cycles (plus the rate limit's
// while a change is large), stated by delay_s().
// Real-time: step() does not allocate, lock or throw.
#pragma once

#include <array>
#include <cstddef>

#include "deflex/model/types.hpp"

namespace deflex {

struct SmootherLimits {
  double cycle_s = 0.008;     ///< the controller's communication interval
  double step_rad = 0.0;      ///< the largest change of the correction in one cycle, per joint
  double acceleration = 0.0;  ///< rad/s^2 the correction may add to the stream
  double jerk = 0.0;          ///< rad/s^3 the correction may add to the stream
};

class CorrectionSmoother {
 public:
  static constexpr std::size_t kMaxTaps = 128;

  /// The smallest N for which the bounds above meet the limits. Throws InputError naming the limit
  /// when a value is not positive and finite, or when it would take more than kMaxTaps (the delay
  /// that needs is given in the message: a smaller step limit is the cure).
  [[nodiscard]] static std::size_t taps_for(const SmootherLimits& limits);

  /// Throws as taps_for(). `joints` in 1..kMaxJoints.
  CorrectionSmoother(const SmootherLimits& limits, int joints);

  /// Starts from `correction` held (rest: no velocity, no acceleration).
  void reset(const JointVector& correction) noexcept;
  /// The next cycle's smoothed correction towards `wanted` (same size as at construction); while held,
  /// towards what it was held at (`wanted` is not read).
  const JointVector& step(const JointVector& wanted) noexcept;
  /// From now on the correction settles where it is (a stream's end): after 2N + 1 more steps its
  /// output is constant, with no velocity, acceleration or jerk (settled()). reset() releases it.
  void hold() noexcept;
  [[nodiscard]] bool holding() const noexcept { return holding_; }
  [[nodiscard]] bool settled() const noexcept { return holding_ && held_steps_ >= 2 * taps_ + 1; }

  [[nodiscard]] std::size_t taps() const noexcept { return taps_; }
  /// The moving averages' delay, (N - 1) cycles, s.
  [[nodiscard]] double delay_s() const noexcept;
  /// The bounds this smoother guarantees on its output (rad/s, rad/s^2, rad/s^3).
  [[nodiscard]] double velocity_bound() const noexcept;
  [[nodiscard]] double acceleration_bound() const noexcept;
  [[nodiscard]] double jerk_bound() const noexcept;

 private:
  // One moving average over the last taps_ values: a ring and its mean, recomputed each cycle from
  // the ring (no running sum that would drift).
  struct Stage {
    std::array<JointVector, kMaxTaps> ring;
    std::size_t next = 0;
  };
  const JointVector& average(Stage& stage, const JointVector& in) noexcept;

  SmootherLimits limits_;
  std::size_t taps_;
  bool holding_ = false;
  std::size_t held_steps_ = 0;
  int joints_;
  JointVector limited_;
  JointVector first_;
  JointVector out_;
  Stage a_;
  Stage b_;
};

}  // namespace deflex
