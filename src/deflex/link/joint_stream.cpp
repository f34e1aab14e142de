// The nominal of a streaming link (see joint_stream.hpp).
#include "deflex/link/joint_stream.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

void JointStreamConfig::validate() const {
  if (!std::isfinite(ramp_in_s) || ramp_in_s < 0.0) {
    throw InputError(fmt::format("stream: ramp-in time must be >= 0 s (got {})", ramp_in_s));
  }
  if (!std::isfinite(start_tolerance_rad) || !(start_tolerance_rad > 0.0)) {
    throw InputError("stream: the start tolerance must be a positive angle");
  }
  if (!std::isfinite(pause_after_s) || !(pause_after_s > 0.0)) {
    throw InputError(fmt::format("stream: the pause silence must be > 0 s (got {})", pause_after_s));
  }
}

JointStream::JointStream(std::shared_ptr<const JointTrajectory> trajectory, const JointStreamConfig& config)
    : trajectory_(std::move(trajectory)), config_(config) {
  config_.validate();
  if (!trajectory_ || trajectory_->size() < 2) {
    throw InputError("stream: no trajectory to stream");
  }
  program_t_s_ = trajectory_->start_time_s();
  offset_ = distance_ = scratch_ = JointVector::Zero(trajectory_->dof());
}

bool JointStream::begin(double t_s, const JointVector& q_feedback) noexcept {
  trajectory_->sample(program_t_s_, scratch_);
  if (q_feedback.size() != scratch_.size() || !q_feedback.allFinite()) {
    distance_.setConstant(HUGE_VAL);
    return false;
  }
  offset_ = q_feedback - scratch_;
  distance_ = offset_.cwiseAbs();
  if (distance_.maxCoeff() > config_.start_tolerance_rad) {
    return false;
  }
  started_ = true;
  last_t_s_ = t_s;
  blend_start_s_ = program_t_s_;
  return true;
}

void JointStream::advance(double t_s, JointVector& q, JointVector& qd) noexcept {
  if (started_) {
    const double dt = t_s - last_t_s_;
    // Only time the controller was talking moves the program (a pause must begin() again first).
    if (dt > 0.0 && dt <= config_.pause_after_s) {
      program_t_s_ = std::min(program_t_s_ + dt, trajectory_->end_time_s());
    }
    last_t_s_ = std::max(last_t_s_, t_s);
  }
  trajectory_->sample(program_t_s_, q, &qd);
  if (finished()) {
    qd.setZero();
  }
  // Smoothstep blend of the start offset from 1 to 0 over the ramp: the first command is where the
  // arm is, and the blend adds no velocity step at either end.
  const double tau = program_t_s_ - blend_start_s_;
  if (config_.ramp_in_s > 0.0 && tau < config_.ramp_in_s) {
    const double u = std::clamp(tau / config_.ramp_in_s, 0.0, 1.0);
    const double w = 1.0 - u * u * (3.0 - 2.0 * u);
    const double dw = -6.0 * u * (1.0 - u) / config_.ramp_in_s;
    q += w * offset_;
    if (!finished()) qd += dw * offset_;
  }
}

}  // namespace deflex
