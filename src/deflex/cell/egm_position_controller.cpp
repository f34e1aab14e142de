// The controller side of EGM position guidance (see egm_position_controller.hpp).
#include "deflex/cell/egm_position_controller.hpp"

#include <cmath>

namespace deflex::cell {

EgmPositionGuidanceController::EgmPositionGuidanceController(const ControllerConfig& config, const JointVector& q_start,
                                                             DatagramTransport& transport,
                                                             const DatagramAddress& sensor)
    : config_(config), transport_(transport), sensor_(sensor), codec_(static_cast<int>(q_start.size())) {
  const auto n = q_start.size();
  buffer_.assign(2048, 0);
  target_ = filtered_target_ = position_ = q_start;
  speed_ref_ = filtered_speed_ = JointVector::Zero(n);
  robot_.feedback_joints_deg = robot_.planned_joints_deg = JointVector::Zero(n);
  robot_.has_planned = true;
  robot_.motor_state = 1;
  robot_.mci_state = 3;
  robot_.rapid_exec_state = 2;
  const auto ticks = static_cast<std::size_t>(std::lround(config_.egm_dead_time_s / config_.servo_period_s));
  delay_target_.assign(ticks + 1, q_start);
  delay_speed_.assign(ticks + 1, JointVector::Zero(n));
}

const JointVector& EgmPositionGuidanceController::tick(double t_s) {
  const double dt = t_s - last_t_s_;
  last_t_s_ = t_s;
  // Answers that have arrived: the newest one is the target.
  DatagramAddress from;
  for (;;) {
    const long n = transport_.receive(buffer_.data(), buffer_.size(), from);
    if (n < 0) break;
    if (static_cast<std::size_t>(n) > buffer_.size() || !(from == sensor_) ||
        !codec_.decode_sensor(buffer_.data(), static_cast<std::size_t>(n), answer_)) {
      ++counters_.ignored;
      continue;
    }
    ++counters_.targets;
    last_answer_s_ = t_s;
    if (stopped_) continue;
    for (int i = 0; i < target_.size(); ++i) target_[i] = deg_to_rad(answer_.planned_joints_deg[i]);
    if (answer_.speed_ref_joints_deg_s.size() == target_.size()) {
      for (int i = 0; i < speed_ref_.size(); ++i) speed_ref_[i] = deg_to_rad(answer_.speed_ref_joints_deg_s[i]);
    } else {
      speed_ref_.setZero();
    }
  }
  if (reset_pending_) reset_reference();
  if (!stopped_ && t_s - last_answer_s_ > config_.egm_comm_timeout_s) {
    stopped_ = true;  // EGM stops: the arm holds where it is
    counters_.timed_out = true;
  }
  if (!stopped_ && dt > 0.0) {
    // The controller's reference filter, then the dead time, then the servo's position loop.
    const double a = config_.egm_lowpass_hz > 0.0 ? 1.0 - std::exp(-2.0 * kPi * config_.egm_lowpass_hz * dt) : 1.0;
    filtered_target_ += a * (target_ - filtered_target_);
    filtered_speed_ += a * (speed_ref_ - filtered_speed_);
    delay_target_[delay_head_] = filtered_target_;
    delay_speed_[delay_head_] = filtered_speed_;
    delay_head_ = (delay_head_ + 1) % delay_target_.size();
    const JointVector& r = delay_target_[delay_head_];  // the oldest entry: dead time ago
    const JointVector& v = delay_speed_[delay_head_];
    position_ += dt * (config_.egm_position_gain_per_s * (r - position_) + v);
  }
  if ((!stopped_ || streaming_after_stop_) && t_s + 1e-12 >= next_send_s_) {
    next_send_s_ += config_.egm_period_s;
    robot_.seqno = ++seqno_;
    robot_.tm_ms = egm_time_stamp_ms(t_s);
    for (int i = 0; i < position_.size(); ++i) {
      robot_.feedback_joints_deg[i] = rad_to_deg(have_encoders_ ? encoders_[i] : position_[i]);
      robot_.planned_joints_deg[i] = rad_to_deg(target_[i]);
    }
    const std::size_t n = codec_.encode_robot(robot_, buffer_.data(), buffer_.size());
    if (n > 0 && transport_.send_to(buffer_.data(), n, sensor_)) ++counters_.sent;
  }
  return position_;
}

void EgmPositionGuidanceController::restart(double t_s, bool reset_reference) {
  seqno_ = 0;
  stopped_ = streaming_after_stop_ = false;
  robot_.mci_state = 3;
  last_answer_s_ = t_s;
  next_send_s_ = t_s;
  // The new EGMRunJoint takes the arm's position as its reference once the sensor's answers already on
  // the way have been read: its first message reports the arm, not deflex's last command (a controller
  // that let an in-flight answer set the new reference would be kinder than one may assume).
  reset_pending_ = reset_reference;
}

void EgmPositionGuidanceController::reset_reference() {
  reset_pending_ = false;
  target_ = filtered_target_ = have_encoders_ ? encoders_ : position_;
  speed_ref_.setZero();
  filtered_speed_.setZero();
  for (auto& q : delay_target_) q = target_;
  for (auto& v : delay_speed_) v.setZero();
}

void EgmPositionGuidanceController::end_session(int mci_state) {
  stopped_ = true;
  streaming_after_stop_ = true;
  robot_.mci_state = mci_state;
}

void EgmPositionGuidanceController::motors_off() {
  stopped_ = true;
  streaming_after_stop_ = true;
  robot_.motor_state = 2;
}

void EgmPositionGuidanceController::encoders(const JointVector& q_motor_rad) {
  encoders_ = q_motor_rad;
  have_encoders_ = true;
}

}  // namespace deflex::cell
