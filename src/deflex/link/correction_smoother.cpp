// Rate limit, then two moving averages in cascade (see correction_smoother.hpp).
#include "deflex/link/correction_smoother.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

void require_positive(double value, const char* name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw InputError(fmt::format("correction smoother: {} must be positive and finite, got {}", name, value));
  }
}

}  // namespace

std::size_t CorrectionSmoother::taps_for(const SmootherLimits& limits) {
  require_positive(limits.cycle_s, "the cycle (s)");
  require_positive(limits.step_rad, "the step limit (rad)");
  require_positive(limits.acceleration, "the acceleration limit (rad/s^2)");
  require_positive(limits.jerk, "the jerk limit (rad/s^3)");
  const double t = limits.cycle_s;
  const double s = limits.step_rad;
  const double for_acceleration = 2.0 * s / (limits.acceleration * t * t);
  const double for_jerk = std::sqrt(4.0 * s / (limits.jerk * t * t * t));
  const double needed = std::ceil(std::max({1.0, for_acceleration, for_jerk}) - 1e-12);
  if (needed > static_cast<double>(kMaxTaps)) {
    throw InputError(fmt::format(
        "correction smoother: a step of {:.6g} rad a cycle of {:.6g} s needs {:.0f} cycles of averaging to stay "
        "within {:.6g} rad/s^2 and {:.6g} rad/s^3 (a delay of {:.3g} s), more than the {} it holds: lower the "
        "correction's rate bound (--max-rate-deg-s) or give it a larger share of the limits",
        s, t, needed, limits.acceleration, limits.jerk, (needed - 1.0) * t, kMaxTaps));
  }
  return static_cast<std::size_t>(needed);
}

CorrectionSmoother::CorrectionSmoother(const SmootherLimits& limits, int joints)
    : limits_(limits), taps_(taps_for(limits)), joints_(joints) {
  if (joints < 1 || joints > kMaxJoints) {
    throw InputError(fmt::format("correction smoother: {} joints, expected 1 to {}", joints, kMaxJoints));
  }
  reset(JointVector::Zero(joints));
}

void CorrectionSmoother::hold() noexcept {
  if (holding_) return;
  holding_ = true;
  held_steps_ = 0;
}

void CorrectionSmoother::reset(const JointVector& correction) noexcept {
  holding_ = false;
  held_steps_ = 0;
  limited_ = correction;
  first_ = correction;
  out_ = correction;
  for (Stage* stage : {&a_, &b_}) {
    for (JointVector& v : stage->ring) v = correction;
    stage->next = 0;
  }
}

const JointVector& CorrectionSmoother::average(Stage& stage, const JointVector& in) noexcept {
  stage.ring[stage.next] = in;
  stage.next = (stage.next + 1) % taps_;
  JointVector& sum = &stage == &a_ ? first_ : out_;
  sum.setZero(joints_);
  for (std::size_t i = 0; i < taps_; ++i) sum += stage.ring[i];
  sum /= static_cast<double>(taps_);
  return sum;
}

const JointVector& CorrectionSmoother::step(const JointVector& wanted) noexcept {
  const double s = limits_.step_rad;
  if (holding_) {
    ++held_steps_;  // the rate-limited value stays: the averages converge on it
  } else {
    for (int j = 0; j < joints_; ++j) {
      const double change = wanted[j] - limited_[j];
      limited_[j] += std::clamp(change, -s, s);
    }
  }
  const JointVector& first = average(a_, limited_);
  return average(b_, first);
}

double CorrectionSmoother::delay_s() const noexcept { return static_cast<double>(taps_ - 1) * limits_.cycle_s; }

double CorrectionSmoother::velocity_bound() const noexcept { return limits_.step_rad / limits_.cycle_s; }

double CorrectionSmoother::acceleration_bound() const noexcept {
  const double t = limits_.cycle_s;
  return 2.0 * limits_.step_rad / (static_cast<double>(taps_) * t * t);
}

double CorrectionSmoother::jerk_bound() const noexcept {
  const double t = limits_.cycle_s;
  const double n = static_cast<double>(taps_);
  return 4.0 * limits_.step_rad / (n * n * t * t * t);
}

}  // namespace deflex
