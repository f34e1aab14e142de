// Link delay measurement (see delay_estimator.hpp).
#include "deflex/online/delay_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

DelayEstimator::DelayEstimator(double initial_delay_s, double window_s)
    : window_s_(window_s), delay_s_(initial_delay_s), last_s_(std::numeric_limits<double>::quiet_NaN()) {
  // Checked once here, so observe_feedback() compares with them without looking again: a NaN delay
  // was the predictive strategy's lead until the first measurement, a NaN window never measured.
  if (!std::isfinite(initial_delay_s) || initial_delay_s < 0.0) {
    throw InputError(
        fmt::format("delay estimator: initial_delay_s must be finite and >= 0 s (got {})", initial_delay_s));
  }
  if (!std::isfinite(window_s) || !(window_s > 0.0)) {
    throw InputError(fmt::format("delay estimator: window_s must be finite and > 0 s (got {})", window_s));
  }
}

void DelayEstimator::record_reference(double t_s, const JointVector& q_ref) noexcept {
  if (!std::isfinite(t_s) || !q_ref.allFinite() ||
      (count_ > 0 && !(t_s > t_[static_cast<std::size_t>((head_ + kRing - 1) % kRing)]))) {
    return;
  }
  const auto h = static_cast<std::size_t>(head_);
  const auto prev = static_cast<std::size_t>((head_ + kRing - 1) % kRing);
  const bool joined = count_ > 0 && q_[prev].size() == q_ref.size();
  // The segment from the previous reference to this one, kept for every match against it.
  segment_[h] = joined ? JointVector(q_ref - q_[prev]) : JointVector::Zero(q_ref.size());
  segment_len2_[h] = segment_[h].squaredNorm();
  travel_[h] = joined ? travel_[prev] + std::sqrt(segment_len2_[h]) : 0.0;
  t_[h] = t_s;
  q_[h] = q_ref;
  head_ = (head_ + 1) % kRing;
  count_ = std::min(count_ + 1, kRing);
}

void DelayEstimator::observe_feedback(double t_s, const JointVector& q_feedback) noexcept {
  if (!q_feedback.allFinite()) {
    return;
  }
  // The arm must be moving: standing (before it starts, or stopped) it matches any reference that
  // passed its place, at any delay.
  constexpr double kMinStepRad = 1e-6;
  const double feedback_step =
      have_feedback_ && last_feedback_.size() == q_feedback.size() ? (q_feedback - last_feedback_).norm() : 0.0;
  const double feedback_dt = t_s - last_feedback_t_;
  const bool moving = have_feedback_ && feedback_step >= kMinStepRad && feedback_dt > 0.0;
  last_feedback_ = q_feedback;
  last_feedback_t_ = t_s;
  have_feedback_ = true;
  if (count_ < 3 || !moving) {
    return;
  }
  const auto at = [&](int k) { return static_cast<std::size_t>((head_ - 1 - k + kRing) % kRing); };
  // The reference must be moving now (at rest, or after it stopped, every recent reference matches
  // the feedback equally), and the matched piece of it must be moving too.
  if ((q_[at(0)] - q_[at(1)]).norm() < kMinStepRad) return;
  double best2 = std::numeric_limits<double>::infinity();  // squared joint distance of the best match
  double best_t = 0.0;
  double best_step = 0.0;
  double best_dt = 0.0;
  int best_k = -1;
  const int n = static_cast<int>(q_feedback.size());
  const double* const f = q_feedback.data();
  // Segments k in [k_from, k_to], k back from the newest. Plain loops over the joints on the segment
  // kept when its reference was recorded: this runs for every feedback sample of a link.
  const auto scan = [&](int k_from, int k_to) {
    for (int k = std::max(1, k_from); k <= k_to && k < count_; ++k) {
      const std::size_t i1 = at(k - 1), i0 = at(k);  // segment from the older i0 to the newer i1
      if (t_s - t_[i0] > window_s_) break;
      if (q_[i0].size() != n || q_[i1].size() != n) return;
      const double* const a = q_[i0].data();
      const double* const d = segment_[i1].data();
      const double len2 = segment_len2_[i1];
      double s = 0.0;
      if (len2 > 0.0) {
        double along = 0.0;
        for (int j = 0; j < n; ++j) along += (f[j] - a[j]) * d[j];
        s = std::clamp(along / len2, 0.0, 1.0);
      }
      double dist2 = 0.0;
      for (int j = 0; j < n; ++j) {
        const double e = a[j] + s * d[j] - f[j];
        dist2 += e * e;
      }
      if (dist2 < best2) {
        best2 = dist2;
        best_t = t_[i0] + s * (t_[i1] - t_[i0]);
        best_step = std::sqrt(len2);
        best_dt = t_[i1] - t_[i0];
        best_k = k;
      }
    }
  };
  // Where the last match was, give or take a few segments (the delay changes slowly); the whole
  // window when that finds the best at its edge, and every 64th sample anyway.
  constexpr int kNear = 6;
  const bool full = last_k_ < 1 || ++since_full_ >= 64;
  if (!full) {
    scan(last_k_ - kNear, last_k_ + kNear);
  }
  if (full || best_k <= std::max(1, last_k_ - kNear) || best_k >= last_k_ + kNear) {
    best2 = std::numeric_limits<double>::infinity();
    best_k = -1;
    scan(1, count_ - 1);
    since_full_ = 0;
  }
  if (best_k < 0) return;
  last_k_ = best_k;
  // How far the reference went from the match to now (cumulative path length).
  const double travel = travel_[at(0)] - travel_[at(best_k)];
  // Ambiguous: the feedback is not on the reference's recent path, or the reference has hardly moved
  // since the match (it rested there).
  if (!(best_step > kMinStepRad) || !(std::sqrt(best2) < 0.1 * travel)) {
    return;
  }
  // A delay line keeps the speed: the arm moves now as fast as the reference did where it matched.
  // An arm settling at the end of a motion creeps far slower than the reference it matches.
  const double speed_ratio = best_dt > 0.0 ? (feedback_step / feedback_dt) / (best_step / best_dt) : 0.0;
  if (!(speed_ratio > 0.5 && speed_ratio < 2.0)) {
    return;
  }
  const double sample = t_s - best_t;
  if (!(sample >= 0.0) || !(sample < window_s_)) return;
  // Once the estimate has settled, a measurement far from it is a mismatch (a reversal, the arm
  // coming to rest), not a change of the link: it is counted and left out.
  const auto far = [](double a, double b) { return std::abs(a - b) > std::max(0.02, 0.5 * b); };
  if (measurements_ >= 20 && far(sample, delay_s_)) {
    ++outliers_;
    // Many in a row that agree with each other are no mismatch: the first estimate was wrong or the
    // link changed. Start again from them. Mismatches that scatter start the count afresh.
    const double run_mean = consecutive_outliers_ > 0 ? outlier_sum_s_ / consecutive_outliers_ : sample;
    if (std::abs(sample - run_mean) > std::max(0.01, 0.25 * run_mean)) {
      consecutive_outliers_ = 0;
      outlier_sum_s_ = 0.0;
    }
    outlier_sum_s_ += sample;
    if (++consecutive_outliers_ < 25) return;
    // The estimate restarts as the mean of the run of them (this sample is added below).
    delay_s_ = outlier_sum_s_ / consecutive_outliers_;
    measurements_ = static_cast<std::uint64_t>(consecutive_outliers_ - 1);
    sum_s_ = outlier_sum_s_ - sample;
  }
  consecutive_outliers_ = 0;
  outlier_sum_s_ = 0.0;
  last_s_ = sample;
  ++measurements_;
  sum_s_ += sample;
  // Running mean that forgets slowly (about the last 50 measurements).
  delay_s_ = measurements_ == 1 ? sample : delay_s_ + 0.02 * (sample - delay_s_);
}

}  // namespace deflex
