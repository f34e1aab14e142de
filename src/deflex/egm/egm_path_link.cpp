// ABB EGM path correction (see egm_path_link.hpp).
#include "deflex/egm/egm_path_link.hpp"

#include <chrono>
#include <cmath>

#include <Eigen/LU>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

const char* to_string(PathCorrFrame f) {
  switch (f) {
    case PathCorrFrame::kTool: return "tool";
    case PathCorrFrame::kFlange: return "flange";
    case PathCorrFrame::kPath: return "path";
  }
  return "unknown";
}

PathCorrFrame parse_path_corr_frame(const std::string& name) {
  if (name == "tool") return PathCorrFrame::kTool;
  if (name == "flange") return PathCorrFrame::kFlange;
  if (name == "path") return PathCorrFrame::kPath;
  throw InputError(fmt::format("path-correction frame '{}' is not tool, flange or path", name));
}

void EgmPathLinkConfig::validate() const {
  receiver.validate();
  if (!std::isfinite(rotation_warning_rad) || rotation_warning_rad < 0.0) {
    throw InputError("EGM path link: the rotation warning must be >= 0 rad");
  }
  if (!std::isfinite(correction_latency_s) || correction_latency_s < 0.0) {
    throw InputError("EGM path link: the correction latency must be >= 0 s");
  }
}

EgmPathLink::EgmPathLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport,
                         const Clock& clock, ForceSource* force, const EgmPathLinkConfig& config)
    : comp_(compensator),
      strategy_(strategy),
      clock_(clock),
      force_(force),
      config_(config),
      receiver_(transport, clock, compensator.model(), with_period(config.receiver, compensator.config().period_s),
                counters_),
      delay_(config.initial_delay_s),
      history_(config.history_cycles, compensator.model().dof()),
      ws_(compensator.model()),
      jac_(6, compensator.model().dof()) {
  config_.validate();
  const int n = compensator.model().dof();
  for (JointVector* q : {&input_.q_planned, &input_.q_feedback, &feedback_, &planned_, &previous_feedback_, &velocity_,
                         &target_, &no_distance_, &sent_offset_joints_, &reference_}) {
    *q = JointVector::Zero(n);
  }
  tx_.assign(512, 0);
  last_ = history_.blank();
}

bool EgmPathLink::correction_frame(const JointVector& q_feedback, Matrix3& base_R_frame) noexcept {
  forward_kinematics(comp_.model(), ws_, q_feedback);
  switch (config_.frame) {
    case PathCorrFrame::kTool:
      base_R_frame = ws_.base_T_tcp.linear();
      return true;
    case PathCorrFrame::kFlange:
      base_R_frame = ws_.base_T_flange.linear();
      return true;
    case PathCorrFrame::kPath: {
      if (!have_direction_) return false;
      const Vector3 x = travel_direction_;
      Vector3 y = ws_.base_T_tcp.linear().col(2).cross(x);
      if (!(y.norm() > 1e-6)) return false;  // travelling along the tool axis: no path frame
      y.normalize();
      base_R_frame.col(0) = x;
      base_R_frame.col(1) = y;
      base_R_frame.col(2) = x.cross(y);
      return true;
    }
  }
  return false;
}

LinkPollResult EgmPathLink::poll(double timeout_s) noexcept {
  bool restarted = false;
  const EgmReceiver::Result got = receiver_.drain(timeout_s, restarted);
  if (got == EgmReceiver::Result::kNothing) return LinkPollResult::kIdle;
  if (got == EgmReceiver::Result::kNoneUsable) return LinkPollResult::kRejected;
  const auto t_read = std::chrono::steady_clock::now();
  const double now = clock_.now_s();
  const EgmRobotMessage& m = receiver_.message();
  for (int i = 0; i < feedback_.size(); ++i) {
    feedback_[i] = deg_to_rad(m.feedback_joints_deg[i]);
    planned_[i] = deg_to_rad(m.planned_joints_deg[i]);
  }
  state_ = LinkState::kRunning;
  if (restarted) {
    have_previous_ = false;  // the direction of travel is kept: the path is the same program
  }

  // Where the arm goes: its joint velocity and the controller's period from the feedback; the
  // direction of travel (path coordinates) from the controller's planned path, which the correction
  // does not move (from the feedback it would chase its own correction), else from the feedback.
  forward_kinematics(comp_.model(), ws_, m.has_planned ? planned_ : feedback_);
  const Vector3 tcp = ws_.base_T_tcp.translation();
  if (have_previous_) {
    const double dt = now - previous_t_s_;
    if (dt > 0.0) {
      velocity_ += 0.5 * ((feedback_ - previous_feedback_) / dt - velocity_);
      period_s_ = period_s_ > 0.0 ? period_s_ + 0.1 * (dt - period_s_) : dt;
      const Vector3 step = tcp - previous_tcp_m_;
      if (step.norm() > 1e-6) {
        travel_direction_ = step.normalized();
        have_direction_ = true;
      }
    }
  } else {
    velocity_.setZero();
  }
  previous_feedback_ = feedback_;
  previous_t_s_ = now;
  previous_tcp_m_ = tcp;
  have_previous_ = true;

  if (m.has_planned) {
    reference_ = planned_ + sent_offset_joints_;
    delay_.record_reference(now, reference_);
  }
  delay_.observe_feedback(now, feedback_);
  // The correction sent now is applied after the servo delay, the channel's latency and on average
  // half a correction period: the predictive strategy evaluates it where the arm will be by then.
  const double lead = delay_.delay_s() + config_.correction_latency_s + 0.5 * period_s_;
  target_ = feedback_;
  if (strategy_.kind() == StrategyKind::kPredictive) {
    target_ += lead * velocity_;
  }
  Matrix3 base_R_frame = Matrix3::Identity();
  const bool frame_ok = correction_frame(feedback_, base_R_frame);
  input_.t_s = now;
  input_.q_planned = target_;
  input_.q_feedback = feedback_;
  const StrategyStatus ss = strategy_.prepare(input_, feedback_, target_, lead, comp_.filter_delay_s());
  input_.hold_to_zero = input_.hold_to_zero || ss != StrategyStatus::kOk || !frame_ok;
  const CycleOutput out = force_ != nullptr ? comp_.step(input_, *force_) : comp_.step(input_);

  LinkCycleRecord& r = last_;
  r.t_s = now;
  r.sequence = m.seqno;
  r.q_nominal = planned_;
  r.q_feedback = feedback_;
  r.q_command = feedback_;
  r.dtheta = out.dtheta;
  r.wrench_base = out.wrench_base;
  r.wrench_measured_base = out.wrench_measured_base;
  r.status = out.status;
  r.replied = false;
  r.delay_s = delay_.delay_s();
  r.arrival = receiver_.arrival();
  if (out.status == CycleStatus::kForceFault || out.status == CycleStatus::kInvalidInput) {
    fault_pending_ = true;
  }
  LinkPollResult result = LinkPollResult::kNotAnswered;
  if (static_cast<int>(out.status) < 0) {
    ++counters_.invalid_cycles;
  } else {
    jacobian(comp_.model(), ws_, target_, EndPoint::kTcp, jac_);
    const Vector3 correction = -(jac_.topRows<3>() * out.dtheta);
    const double rotation = (jac_.bottomRows<3>() * out.dtheta).norm();
    r.tcp_correction_m = correction;
    r.rotation_uncorrected_rad = rotation;
    max_rotation_rad_ = std::max(max_rotation_rad_, rotation);
    if (rotation > config_.rotation_warning_rad) ++rotation_warnings_;
    // The last check before anything leaves deflex: the offset within the TCP bound of "no offset".
    const double bound = comp_.config().max_tcp_correction_m * (1.0 + 1e-9) + 1e-12;
    if (!correction.allFinite() || correction.norm() > bound) {
      ++counters_.guard_trips;
      fault_pending_ = true;
    } else {
      reply_.seqno = ++reply_seq_;
      reply_.tm_ms = egm_time_stamp_ms(now);
      reply_.pos_mm = frame_ok ? Vector3(base_R_frame.transpose() * correction * 1e3) : Vector3::Zero();
      const double age_ms = std::clamp(out.force_age_s * 1e3, 0.0, 4.0e9);
      reply_.age_ms = static_cast<std::uint32_t>(age_ms);
      const std::size_t n = receiver_.codec().encode_path_corr(reply_, tx_.data(), tx_.size());
      if (n > 0 && receiver_.reply(tx_.data(), n)) {
        r.replied = true;
        result = LinkPollResult::kAnswered;
        // The joints' share of this offset, orientation held (6-axis arms; a fixed-size solve, no
        // allocation). A singular Jacobian leaves the previous value: the delay measurement only.
        if (comp_.model().dof() == 6 && frame_ok) {
          const Eigen::Matrix<double, 6, 6> j6 = jac_;
          Eigen::Matrix<double, 6, 1> twist;
          twist << correction, Vector3::Zero();
          const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> lu(j6);
          if (std::abs(lu.determinant()) > 1e-9) {
            const Eigen::Matrix<double, 6, 1> dq = lu.solve(twist);
            if (dq.allFinite()) sent_offset_joints_ = dq;
          }
        }
      } else if (n == 0) {
        ++counters_.send_errors;
      }
    }
  }
  r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count();
  history_.record(r);
  return result;
}

}  // namespace deflex
