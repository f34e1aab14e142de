// The arm's joint velocity and the controller's period, estimated from the feedback a link decodes each
// cycle, and the target the predictive strategy evaluates: where the feedback will be after the lead.
// One estimate for every link that corrects a program the controller runs itself (RSI, EGM path
// correction); the links that stream the program take the target from the program instead.
#pragma once

#include "deflex/model/types.hpp"

namespace deflex {

/// Fixed size after construction: observe() and lead() never allocate or throw.
class FeedbackMotion {
 public:
  explicit FeedbackMotion(int dof = 0)
      : previous_(JointVector::Zero(dof)), velocity_(JointVector::Zero(dof)), target_(JointVector::Zero(dof)) {}

  /// A new session: the next sample starts the estimate afresh (its velocity is zero).
  void restart() noexcept { have_previous_ = false; }

  /// The feedback at `t_s`. Returns the time since the previous sample, s (0 for the first of a
  /// session, or a sample not after it). The velocity is a first-order filter of the feedback's
  /// finite differences (half of each new one: the feedback is the encoders', already smooth); the
  /// period a slower one (a tenth), since it only scales the path correction's lead.
  double observe(double t_s, const JointVector& q) noexcept {
    double dt = 0.0;
    if (have_previous_) {
      dt = t_s - previous_t_s_;
      if (dt > 0.0) {
        velocity_ += 0.5 * ((q - previous_) / dt - velocity_);
        period_s_ = period_s_ > 0.0 ? period_s_ + 0.1 * (dt - period_s_) : dt;
      } else {
        dt = 0.0;
      }
    } else {
      velocity_.setZero();
    }
    previous_ = q;
    previous_t_s_ = t_s;
    have_previous_ = true;
    return dt;
  }

  /// `from` advanced by `lead_s` at the estimated velocity (the predictive strategy's target); `from`
  /// itself when `predict` is false.
  const JointVector& lead(const JointVector& from, double lead_s, bool predict) noexcept {
    target_ = from;
    if (predict) target_ += lead_s * velocity_;
    return target_;
  }

  [[nodiscard]] const JointVector& velocity() const { return velocity_; }
  /// The controller's period as the feedback arrives, s (0 before two samples).
  [[nodiscard]] double period_s() const { return period_s_; }

 private:
  JointVector previous_, velocity_, target_;
  double previous_t_s_ = 0.0;
  double period_s_ = 0.0;
  bool have_previous_ = false;
};

}  // namespace deflex
