// The nominal of a streaming link (see joint_stream.hpp).
#include "deflex/link/joint_stream.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

void JointStreamConfig::validate() const {
  if (!std::isfinite(ramp_in_s) || ramp_in_s < 0.0 || ramp_in_s > 600.0) {
    throw InputError(fmt::format("stream: ramp-in time must be 0..600 s (got {})", ramp_in_s));
  }
  if (!std::isfinite(start_tolerance_rad) || !(start_tolerance_rad > 0.0) || start_tolerance_rad > kPi / 18.0) {
    throw InputError("stream: the start tolerance must be a positive angle of at most 10 deg");
  }
}

JointStream::JointStream(std::shared_ptr<const JointTrajectory> trajectory, const JointStreamConfig& config)
    : trajectory_(std::move(trajectory)), config_(config) {
  config_.validate();
  if (!trajectory_ || trajectory_->size() < 2) {
    throw InputError("stream: no trajectory to stream");
  }
  program_t_s_ = trajectory_->start_time_s();
  offset_ = distance_ = scratch_ = scratch_velocity_ = JointVector::Zero(trajectory_->dof());
}

bool JointStream::begin(const JointVector& anchor, const JointVector& dtheta) noexcept {
  trajectory_->sample(program_t_s_, scratch_);
  if (anchor.size() != scratch_.size() || dtheta.size() != scratch_.size() || !anchor.allFinite() ||
      !dtheta.allFinite()) {
    distance_.setConstant(HUGE_VAL);
    return false;
  }
  // The command would be program - dtheta; the controller holds the anchor.
  scratch_velocity_ = anchor - (scratch_ - dtheta);
  distance_ = scratch_velocity_.cwiseAbs();
  if (distance_.maxCoeff() > config_.start_tolerance_rad) {
    return false;
  }
  offset_ = scratch_velocity_;
  blend_t_s_ = 0.0;
  blend_cycles_ = 0;
  started_ = true;
  return true;
}

void JointStream::sample(JointVector& program, JointVector& program_velocity, JointVector& blend,
                         JointVector& blend_velocity) const noexcept {
  trajectory_->sample(program_t_s_, program, &program_velocity);
  if (finished()) program_velocity.setZero();
  if (stopping()) program_velocity *= speed_factor();
  // Smoothstep from 1 to 0 over the ramp: the first command is the anchor, and the blend adds no
  // velocity step at either end.
  if (config_.ramp_in_s > 0.0 && blend_t_s_ < config_.ramp_in_s) {
    const double u = std::clamp(blend_t_s_ / config_.ramp_in_s, 0.0, 1.0);
    blend = (1.0 - u * u * (3.0 - 2.0 * u)) * offset_;
    blend_velocity = (-6.0 * u * (1.0 - u) / config_.ramp_in_s) * offset_;
  } else {
    blend.setZero();
    blend_velocity.setZero();
  }
}

void JointStream::consumed(double period_s) noexcept {
  if (!started_ || !(period_s > 0.0)) return;
  ++blend_cycles_;
  blend_t_s_ = static_cast<double>(blend_cycles_) * period_s;
  if (stopping()) {
    // The program moves by the integral of the speed factor 1 - (3u^2 - 2u^3), u = t/T, over this
    // cycle: (t1 - t0) - T (F(u1) - F(u0)) with F(u) = u^3 - u^4/2.
    const double u0 = std::min(stop_elapsed_s_, stop_ramp_s_) / stop_ramp_s_;
    const double u1 = std::min(stop_elapsed_s_ + period_s, stop_ramp_s_) / stop_ramp_s_;
    stop_elapsed_s_ += period_s;
    const auto f = [](double u) { return u * u * u - 0.5 * u * u * u * u; };
    program_t_s_ = std::min(program_t_s_ + stop_ramp_s_ * ((u1 - u0) - (f(u1) - f(u0))), trajectory_->end_time_s());
    return;
  }
  if (program_t_s_ < trajectory_->end_time_s()) ++cycles_;
  program_t_s_ =
      std::min(trajectory_->start_time_s() + static_cast<double>(cycles_) * period_s, trajectory_->end_time_s());
}

void JointStream::begin_stop(double ramp_s) noexcept {
  if (stopping() || !(ramp_s > 0.0) || !std::isfinite(ramp_s)) return;
  stop_ramp_s_ = ramp_s;
  stop_elapsed_s_ = 0.0;
}

double JointStream::speed_factor() const {
  if (!stopping()) return 1.0;
  // A smoothstep down from 1 to 0: no step in the deceleration at either end, so the stop adds a
  // bounded jerk (6 v / T^2 at most) to the stream, which a controller that checks the jerk of what it
  // is sent (FANUC's Stream Motion) accepts where a linear ramp's v / (T x cycle) would stop it.
  const double u = std::clamp(stop_elapsed_s_ / stop_ramp_s_, 0.0, 1.0);
  return 1.0 - u * u * (3.0 - 2.0 * u);
}

}  // namespace deflex
