// Measures a controller link's delay: how long after a joint reference is given the robot's feedback
// shows it. Each feedback sample is matched against the recent references (the nearest point on the
// reference's polyline, by joint distance), and the time between them is one measurement; the
// estimate is their running average. Only samples taken while both the reference and the feedback
// move, the feedback as fast as the reference did where it matched (a delay line keeps the speed),
// are used (at rest every reference matches; an arm that has not started yet matches the
// reference's start at any delay), and once settled a measurement far from the estimate is left out (a run of
// them that agree with each other, a link whose delay changed, starts the estimate afresh from them;
// scattered mismatches, as when the arm comes to rest, never do). The predictive strategy leads by this delay. Fixed
// ring: no allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "deflex/model/types.hpp"

namespace deflex {

/// Thread safety: one thread at a time (the link's).
class DelayEstimator {
 public:
  /// `initial_delay_s`: the estimate until the first measurement. `window_s`: how far back a
  /// reference is looked for (longer than any delay expected). Throws InputError unless the delay is
  /// finite and >= 0 and the window finite and > 0.
  explicit DelayEstimator(double initial_delay_s = 0.05, double window_s = 0.5);

  /// The reference the controller was given (or reports following) at time t_s.
  void record_reference(double t_s, const JointVector& q_ref) noexcept;
  /// A feedback sample at time t_s; updates the estimate when it can be matched.
  void observe_feedback(double t_s, const JointVector& q_feedback) noexcept;

  [[nodiscard]] double delay_s() const { return delay_s_; }
  [[nodiscard]] bool measured() const { return measurements_ > 0; }
  [[nodiscard]] std::uint64_t measurements() const { return measurements_; }
  /// The last single measurement, s (NaN before the first).
  [[nodiscard]] double last_measurement_s() const { return last_s_; }
  /// The mean of every measurement taken, s (NaN before the first).
  [[nodiscard]] double mean_s() const {
    return measurements_ > 0 ? sum_s_ / static_cast<double>(measurements_) : last_s_;
  }
  /// Measurements left out as mismatches.
  [[nodiscard]] std::uint64_t outliers() const { return outliers_; }

 private:
  static constexpr int kRing = 256;
  static constexpr double kMinStepRad = 1e-6;  // a step below this is standing still
  struct FeedbackMotion {
    double step = 0.0;  // since the previous sample, rad
    double dt = 0.0;    // s
    bool moving = false;
  };
  // The nearest point of the recent references to a feedback sample.
  struct Match {
    double dist2 = std::numeric_limits<double>::infinity();  // squared joint distance, rad^2
    double t = 0.0;                                          // the reference's time there, s
    double step = 0.0;                                       // the matched segment's length, rad
    double dt = 0.0;                                         // and its duration, s
    int k = -1;                                              // segments back from the newest
  };
  [[nodiscard]] std::size_t ring_index(int k) const noexcept {
    return static_cast<std::size_t>((head_ - 1 - k + kRing) % kRing);
  }
  FeedbackMotion note_feedback(double t_s, const JointVector& q_feedback) noexcept;
  Match match_reference(double t_s, const JointVector& q_feedback) noexcept;
  void scan(double t_s, const JointVector& q_feedback, int k_from, int k_to, Match& best) const noexcept;
  void take_measurement(double sample) noexcept;

  std::array<double, kRing> t_{};
  std::array<JointVector, kRing> q_{};
  std::array<double, kRing> travel_{};        // cumulative path length of the references, rad
  std::array<JointVector, kRing> segment_{};  // from the previous reference to this one, rad
  std::array<double, kRing> segment_len2_{};  // its squared length, rad^2
  int head_ = 0, count_ = 0;
  double window_s_;
  double delay_s_;
  double last_s_;
  std::uint64_t measurements_ = 0;
  std::uint64_t outliers_ = 0;
  int consecutive_outliers_ = 0;  // in a row, and agreeing with each other (a changed link)
  double outlier_sum_s_ = 0.0;    // their sum
  JointVector last_feedback_;     // the previous feedback sample: the arm must be moving too
  double last_feedback_t_ = 0.0;
  bool have_feedback_ = false;
  int last_k_ = 0;      // segments back from the newest reference at the last match
  int since_full_ = 0;  // samples since the last search of the whole window
  double sum_s_ = 0.0;
};

}  // namespace deflex
