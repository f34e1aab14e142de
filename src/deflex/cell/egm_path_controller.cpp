// The controller side of EGM path correction (see egm_path_controller.hpp).
#include "deflex/cell/egm_path_controller.hpp"

#include <cmath>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "deflex/text/errors.hpp"

namespace deflex::cell {

EgmPathCorrectionController::EgmPathCorrectionController(const ControllerConfig& config, const RobotModel& kinematics,
                                                         std::shared_ptr<const JointTrajectory> program,
                                                         DatagramTransport& transport, const DatagramAddress& sensor)
    : config_(config),
      model_(kinematics),
      ws_(model_),
      jac_(6, model_.dof()),
      program_(std::move(program)),
      transport_(transport),
      sensor_(sensor),
      codec_(model_.dof()) {
  if (config_.path_corr_frame == "tool") {
    frame_ = Frame::kTool;
  } else if (config_.path_corr_frame == "flange") {
    frame_ = Frame::kFlange;
  } else if (config_.path_corr_frame == "path") {
    frame_ = Frame::kPath;
  } else {
    throw InputError(
        fmt::format("controller: path-correction frame '{}' is not tool, flange or path", config_.path_corr_frame));
  }
  buffer_.assign(2048, 0);
  pending_.resize(64);
  const int n = model_.dof();
  planned_ = position_ = program_->points().front();
  planned_velocity_ = JointVector::Zero(n);
  robot_.feedback_joints_deg = robot_.planned_joints_deg = JointVector::Zero(n);
  robot_.has_planned = true;
  robot_.motor_state = 1;
  robot_.mci_state = 3;
  robot_.rapid_exec_state = 2;
}

const JointVector& EgmPathCorrectionController::tick(double t_s) {
  const double dt = t_s - last_t_s_;
  last_t_s_ = t_s;
  DatagramAddress from;
  for (;;) {
    const long n = transport_.receive(buffer_.data(), buffer_.size(), from);
    if (n < 0) break;
    if (static_cast<std::size_t>(n) > buffer_.size() || !(from == sensor_) ||
        !codec_.decode_path_corr(buffer_.data(), static_cast<std::size_t>(n), answer_)) {
      ++counters_.ignored;
      continue;
    }
    ++counters_.targets;
    if (pending_count_ == pending_.size()) {  // full: the oldest is dropped
      pending_head_ = (pending_head_ + 1) % pending_.size();
      --pending_count_;
    }
    Pending& p = pending_[(pending_head_ + pending_count_) % pending_.size()];
    p.due_s = t_s + config_.path_corr_dead_time_s;
    p.offset_frame_m = answer_.pos_mm * 1e-3;
    ++pending_count_;
  }
  while (pending_count_ > 0 && pending_[pending_head_].due_s <= t_s + 1e-12) {
    active_frame_m_ = pending_[pending_head_].offset_frame_m;  // absolute: the newest replaces
    pending_head_ = (pending_head_ + 1) % pending_.size();
    --pending_count_;
  }

  program_->sample(t_s, planned_, &planned_velocity_);
  jacobian(model_, ws_, planned_, EndPoint::kTcp, jac_);
  Matrix3 base_R_frame;
  switch (frame_) {
    case Frame::kTool:
      base_R_frame = ws_.base_T_tcp.linear();
      break;
    case Frame::kFlange:
      base_R_frame = ws_.base_T_flange.linear();
      break;
    case Frame::kPath: {
      const Vector3 v = jac_.topRows<3>() * planned_velocity_;
      if (v.norm() > 1e-6) direction_ = v.normalized();
      Vector3 y = ws_.base_T_tcp.linear().col(2).cross(direction_);
      y = y.norm() > 1e-9 ? Vector3(y.normalized()) : Vector3::UnitY();
      base_R_frame.col(0) = direction_;
      base_R_frame.col(1) = y;
      base_R_frame.col(2) = direction_.cross(y);
      break;
    }
  }
  const double a =
      config_.path_corr_filter_s > 0.0 && dt > 0.0 ? 1.0 - std::exp(-dt / config_.path_corr_filter_s) : 1.0;
  applied_m_ += a * (base_R_frame * active_frame_m_ - applied_m_);
  // The TCP moves by the offset, its orientation stays: solve J dq = [offset; 0].
  Eigen::Matrix<double, 6, 1> twist;
  twist << applied_m_, Vector3::Zero();
  // A 6-joint arm's Jacobian is square: LU (a quarter of the QR's cost, every servo tick); a longer
  // chain takes the least-squares answer.
  const JointVector dq = jac_.cols() == 6 ? JointVector(Matrix6(jac_).partialPivLu().solve(twist))
                                          : JointVector(jac_.colPivHouseholderQr().solve(twist));
  position_ = planned_ + dq;

  if (t_s + 1e-12 >= next_send_s_) {
    next_send_s_ += config_.path_corr_period_s;
    robot_.seqno = ++seqno_;
    robot_.tm_ms = egm_time_stamp_ms(t_s);
    for (int i = 0; i < position_.size(); ++i) {
      robot_.feedback_joints_deg[i] = rad_to_deg(have_encoders_ ? encoders_[i] : position_[i]);
      robot_.planned_joints_deg[i] = rad_to_deg(planned_[i]);
    }
    const std::size_t n = codec_.encode_robot(robot_, buffer_.data(), buffer_.size());
    if (n > 0 && transport_.send_to(buffer_.data(), n, sensor_)) ++counters_.sent;
  }
  return position_;
}

void EgmPathCorrectionController::restart() {
  seqno_ = 0;
  pending_count_ = 0;
  active_frame_m_.setZero();
  applied_m_.setZero();
}

void EgmPathCorrectionController::encoders(const JointVector& q_motor_rad) {
  encoders_ = q_motor_rad;
  have_encoders_ = true;
}

}  // namespace deflex::cell
