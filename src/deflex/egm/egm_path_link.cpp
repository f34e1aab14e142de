// ABB EGM path correction (see egm_path_link.hpp).
#include "deflex/egm/egm_path_link.hpp"

#include <chrono>
#include <cmath>

#include <Eigen/LU>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

const char* to_string(PathCorrFrame f) {
  switch (f) {
    case PathCorrFrame::kTool:
      return "tool";
    case PathCorrFrame::kFlange:
      return "flange";
    case PathCorrFrame::kPath:
      return "path";
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
  stop.validate();
  if (!std::isfinite(rotation_warning_rad) || rotation_warning_rad < 0.0) {
    throw InputError("EGM path link: the rotation warning must be >= 0 rad");
  }
  if (!std::isfinite(correction_latency_s) || correction_latency_s < 0.0) {
    throw InputError("EGM path link: the correction latency must be >= 0 s");
  }
}

namespace {
CommandLimits path_limits(const OnlineCompensator& c, const EgmPathLinkConfig& config) {
  config.validate();
  return command_limits(CommandForm::kTcpOffset, c.config(), c.model().dof());
}
}  // namespace

EgmPathLink::EgmPathLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport,
                         const Clock& clock, const EgmPathLinkConfig& config)
    : ControllerLink(compensator, strategy, clock, path_limits(compensator, config), config.stop,
                     config.history_cycles),
      config_(config),
      receiver_(transport, clock, compensator.model(), with_period(config.receiver, compensator.config().period_s),
                counters_),
      delay_(config.initial_delay_s),
      jac_(6, compensator.model().dof()) {
  const int n = compensator.model().dof();
  for (JointVector* q : {&feedback_, &planned_, &sent_offset_joints_, &reference_, &previous_path_q_}) {
    *q = JointVector::Zero(n);
  }
  tx_.assign(512, 0);
}

bool EgmPathLink::correction_frame(const JointVector& q_feedback, Matrix3& base_R_frame) noexcept {
  const Workspace& ws = cycle_.compensator().frames().at(q_feedback);  // the cycle's, computed once
  switch (config_.frame) {
    case PathCorrFrame::kTool:
      base_R_frame = ws.base_T_tcp.linear();
      return true;
    case PathCorrFrame::kFlange:
      base_R_frame = ws.base_T_flange.linear();
      return true;
    case PathCorrFrame::kPath: {
      if (!have_direction_) return false;
      const Vector3 x = travel_direction_;
      Vector3 y = ws.base_T_tcp.linear().col(2).cross(x);
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

bool EgmPathLink::controller_state(const EgmRobotMessage& m) noexcept {
  if (m.motor_state == 2) {
    stop_link(LinkStopCause::kController,
              "the controller reports its motors off (EgmRobot motorState OFF: an emergency or protective stop)");
    return false;
  }
  if (m.mci_state == 3) {
    egm_ran_ = true;
  } else if ((m.mci_state == 1 || m.mci_state == 2) && egm_ran_) {
    if (m.mci_state == 2) {
      stop_link(LinkStopCause::kEnded, "the controller ended path correction (mciState STOPPED: EGMStop)");
    } else {
      stop_link(LinkStopCause::kController, "the controller reports an EGM error (mciState ERROR)");
    }
    return false;
  }
  return true;
}

std::string EgmPathLink::protocol_summary() const {
  return fmt::format(
      "egm-path: largest TCP rotation the model predicted {:.3f} mrad ({} cycles above {:g} mrad; path "
      "correction cannot rotate)",
      max_rotation_rad_ * 1e3, rotation_warnings_, config_.rotation_warning_rad * 1e3);
}

LinkPollResult EgmPathLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kStopped) {
    bool ignored = false;
    (void)receiver_.drain(0.0, ignored);
    return announce_terminal();
  }
  bool restarted = false;
  const EgmReceiver::Result got = receiver_.drain(timeout_s, restarted);
  const double now = clock_.now_s();
  if (got != EgmReceiver::Result::kMessage) {
    if (apply_silence_rules(now)) return announce_terminal();
    return got == EgmReceiver::Result::kNothing ? LinkPollResult::kIdle : LinkPollResult::kRejected;
  }
  const auto t_read = std::chrono::steady_clock::now();
  const EgmRobotMessage& m = receiver_.message();
  for (int i = 0; i < feedback_.size(); ++i) {
    feedback_[i] = deg_to_rad(m.feedback_joints_deg[i]);
    planned_[i] = deg_to_rad(m.planned_joints_deg[i]);
  }
  heard(now);
  if (!controller_state(m)) return announce_terminal();
  const bool session_start = restarted || state_ == LinkState::kWaiting;
  if (session_start) {
    // A path-correction session on the controller starts from no offset: so does deflex's correction
    // (it then ramps in at the rate bound), or the first answer would step the path. Without a silence
    // before it the controller may still apply the last offset sent: the next one must step from both.
    if (stop_if_anchor_unreachable(cycle_.reanchor_gap(Vector3(Vector3::Zero())), "the controller's path correction")) {
      return announce_terminal();
    }
    cycle_.restart_from_zero(after_silence());
    cycle_.motion().restart();  // the direction of travel is kept: the path is the same program
    state_ = LinkState::kRunning;
  }

  track_motion(now, m.has_planned);
  return answer(now, m.seqno, session_start, t_read);
}

// Where the arm goes: its joint velocity and the controller's period from the feedback; the
// direction of travel (path coordinates); the delay between the reference and the feedback.
void EgmPathLink::track_motion(double now, bool has_planned) noexcept {
  // The direction of travel from the controller's planned path, which the correction
  // does not move (from the feedback it would chase its own correction), else from the feedback: the
  // TCP's step as the Jacobian at the feedback (the cycle's frames, no kinematics of its own) maps the
  // joints' step, exact to first order in a 4-48 ms step.
  const JointVector& path_q = has_planned ? planned_ : feedback_;
  const double dt = cycle_.motion().observe(now, feedback_);
  if (dt > 0.0 && config_.frame == PathCorrFrame::kPath) {
    const Workspace& ws = cycle_.compensator().frames().at(feedback_);
    point_jacobian(ws, ws.base_T_tcp.translation(), jac_);
    const Vector3 step = jac_.topRows<3>() * (path_q - previous_path_q_);
    if (step.norm() > 1e-6) {
      travel_direction_ = step.normalized();
      have_direction_ = true;
    }
  }
  previous_path_q_ = path_q;

  if (has_planned) {
    reference_ = planned_ + sent_offset_joints_;
    delay_.record_reference(now, reference_);
  }
  delay_.observe_feedback(now, feedback_);
}

// The cycle for this message, and the answer: the whole TCP offset in the correction frame.
LinkPollResult EgmPathLink::answer(double now, std::uint32_t seqno, bool session_start,
                                   std::chrono::steady_clock::time_point t_read) noexcept {
  // The correction sent now is applied after the servo delay, the channel's latency and on average
  // half a correction period: the predictive strategy evaluates it where the arm will be by then.
  const double lead = delay_.delay_s() + config_.correction_latency_s + 0.5 * cycle_.motion().period_s();
  Matrix3 base_R_frame = Matrix3::Identity();
  if (correction_frame(feedback_, base_R_frame)) {
    last_frame_ = base_R_frame;
    have_frame_ = true;
  }
  CycleRequest rq;
  rq.t_s = now;
  rq.sequence = seqno;
  rq.nominal = &planned_;
  rq.feedback = &feedback_;
  rq.target = &cycle_.lead_target(feedback_, lead);
  rq.delay_s = delay_.delay_s();
  rq.lead_s = lead;
  // No frame yet (path coordinates before the arm moved): nothing can be expressed, the correction
  // is held at zero. Later, a moment without a frame keeps the last one.
  rq.hold = !have_frame_ || ramping_down_;  // a planned stop ramps the correction out
  rq.session_start = session_start;
  rq.arrival = receiver_.arrival();
  const LinkCycle::Verdict verdict = cycle_.run(rq);
  const auto compute = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count(); };
  if (verdict != LinkCycle::Verdict::kSend) return cycle_not_passed(verdict, compute());
  // The rotation the model predicts, which this mode cannot correct.
  const Workspace& at_target = cycle_.compensator().frames().at(*rq.target);  // the compensator's, computed
  point_jacobian(at_target, at_target.base_T_tcp.translation(), jac_);
  const double rotation = (jac_.bottomRows<3>() * cycle_.output().dtheta).norm();
  cycle_.note_uncorrected_rotation(rotation);
  max_rotation_rad_ = std::max(max_rotation_rad_, rotation);
  if (rotation > config_.rotation_warning_rad) ++rotation_warnings_;
  const Vector3& correction = cycle_.tcp_offset_m();
  reply_.seqno = ++reply_seq_;
  reply_.tm_ms = egm_time_stamp_ms(now);
  reply_.pos_mm = Vector3(last_frame_.transpose() * correction * 1e3);
  const double age_ms = std::clamp(cycle_.output().force_age_s * 1e3, 0.0, 4.0e9);
  reply_.age_ms = static_cast<std::uint32_t>(age_ms);
  const std::size_t n = receiver_.codec().encode_path_corr(reply_, tx_.data(), tx_.size());
  if (n == 0) ++counters_.send_errors;
  if (n == 0 || !receiver_.reply(tx_.data(), n)) {
    cycle_.not_sent(compute());
    return LinkPollResult::kNotAnswered;
  }
  cycle_.sent(compute(), receiver_.answer_time_s(clock_.now_s()));
  note_sent_offset(correction);
  stop_when_correction_gone();
  return LinkPollResult::kAnswered;
}

// The joints' share of the offset sent, orientation held (6-axis arms; a fixed-size solve, no
// allocation), at the target's Jacobian (jac_). A singular Jacobian leaves the previous value: the
// delay measurement only.
void EgmPathLink::note_sent_offset(const Vector3& correction) noexcept {
  if (cycle_.compensator().model().dof() != 6) return;
  const Eigen::Matrix<double, 6, 6> j6 = jac_;
  Eigen::Matrix<double, 6, 1> twist;
  twist << correction, Vector3::Zero();
  const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> lu(j6);
  if (std::abs(lu.determinant()) > 1e-9) {
    const Eigen::Matrix<double, 6, 1> dq = lu.solve(twist);
    if (dq.allFinite()) sent_offset_joints_ = dq;
  }
}

}  // namespace deflex
