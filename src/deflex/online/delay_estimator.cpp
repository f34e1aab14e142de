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

// A feedback sample is measured in three stages: is the arm moving (else any reference matches), where
// on the recent references it is (the match), and is the delay that match gives a measurement.
void DelayEstimator::observe_feedback(double t_s, const JointVector& q_feedback) noexcept {
  if (!q_feedback.allFinite()) {
    return;
  }
  const FeedbackMotion motion = note_feedback(t_s, q_feedback);
  if (count_ < 3 || !motion.moving) {
    return;
  }
  // The reference must be moving now (at rest, or after it stopped, every recent reference matches
  // the feedback equally), and the matched piece of it must be moving too.
  if ((q_[ring_index(0)] - q_[ring_index(1)]).norm() < kMinStepRad) return;
  const Match m = match_reference(t_s, q_feedback);
  if (m.k < 0) return;
  last_k_ = m.k;
  // How far the reference went from the match to now (cumulative path length).
  const double travel = travel_[ring_index(0)] - travel_[ring_index(m.k)];
  // Ambiguous: the feedback is not on the reference's recent path, or the reference has hardly moved
  // since the match (it rested there).
  if (!(m.step > kMinStepRad) || !(std::sqrt(m.dist2) < 0.1 * travel)) {
    return;
  }
  // A delay line keeps the speed: the arm moves now as fast as the reference did where it matched.
  // An arm settling at the end of a motion creeps far slower than the reference it matches.
  const double speed_ratio = m.dt > 0.0 ? (motion.step / motion.dt) / (m.step / m.dt) : 0.0;
  if (!(speed_ratio > 0.5 && speed_ratio < 2.0)) {
    return;
  }
  const double sample = t_s - m.t;
  if (!(sample >= 0.0) || !(sample < window_s_)) return;
  take_measurement(sample);
}

DelayEstimator::FeedbackMotion DelayEstimator::note_feedback(double t_s, const JointVector& q_feedback) noexcept {
  // The arm must be moving: standing (before it starts, or stopped) it matches any reference that
  // passed its place, at any delay.
  FeedbackMotion motion;
  motion.step =
      have_feedback_ && last_feedback_.size() == q_feedback.size() ? (q_feedback - last_feedback_).norm() : 0.0;
  motion.dt = t_s - last_feedback_t_;
  motion.moving = have_feedback_ && motion.step >= kMinStepRad && motion.dt > 0.0;
  last_feedback_ = q_feedback;
  last_feedback_t_ = t_s;
  have_feedback_ = true;
  return motion;
}

// Segments k in [k_from, k_to], k back from the newest. Plain loops over the joints on the segment
// kept when its reference was recorded: this runs for every feedback sample of a link.
void DelayEstimator::scan(double t_s, const JointVector& q_feedback, int k_from, int k_to, Match& best) const noexcept {
  const int n = static_cast<int>(q_feedback.size());
  const double* const f = q_feedback.data();
  for (int k = std::max(1, k_from); k <= k_to && k < count_; ++k) {
    const std::size_t i1 = ring_index(k - 1), i0 = ring_index(k);  // segment from the older i0 to the newer i1
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
    if (dist2 < best.dist2) {
      best = Match{dist2, t_[i0] + s * (t_[i1] - t_[i0]), std::sqrt(len2), t_[i1] - t_[i0], k};
    }
  }
}

// Where the last match was, give or take a few segments (the delay changes slowly); the whole
// window when that finds the best at its edge, and every 64th sample anyway.
DelayEstimator::Match DelayEstimator::match_reference(double t_s, const JointVector& q_feedback) noexcept {
  constexpr int kNear = 6;
  Match best;
  const bool full = last_k_ < 1 || ++since_full_ >= 64;
  if (!full) {
    scan(t_s, q_feedback, last_k_ - kNear, last_k_ + kNear, best);
  }
  if (full || best.k <= std::max(1, last_k_ - kNear) || best.k >= last_k_ + kNear) {
    best = Match{};
    scan(t_s, q_feedback, 1, count_ - 1, best);
    since_full_ = 0;
  }
  return best;
}

void DelayEstimator::take_measurement(double sample) noexcept {
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
