// KUKA RSI axis correction (see rsi_link.hpp).
#include "deflex/rsi/rsi_link.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

void RsiLinkConfig::validate() const {
  if (!valid_rsi_sentype(sentype)) {
    throw InputError(fmt::format("RSI link: SENTYPE '{}' must be 1..32 letters, digits, '_' or '-', starting with a "
                                 "letter (the controller's <SENTYPE>)",
                                 sentype));
  }
  if (max_document_bytes < 64 || max_document_bytes > 65507) {
    throw InputError("RSI link: max_document_bytes must be 64..65507");
  }
  if (!std::isfinite(restart_silence_s) || !(restart_silence_s > 0.0)) {
    throw InputError("RSI link: the restart silence must be > 0 s");
  }
  if (ipoc_max_ahead_ms < 1 || confirm_jump < 1 || confirm_jump > 1000) {
    throw InputError("RSI link: ipoc_max_ahead_ms must be >= 1 and confirm_jump 1..1000");
  }
  if (!std::isfinite(correction_latency_s) || correction_latency_s < 0.0) {
    throw InputError("RSI link: the correction latency must be >= 0 s");
  }
  if (!std::isfinite(initial_delay_s) || initial_delay_s < 0.0) {
    throw InputError("RSI link: the initial delay must be >= 0 s");
  }
}

namespace {
// The IPOC is both the sequence number and the time stamp: 64 bits of milliseconds, growing by the
// period every cycle, never starting again from a small number.
ControllerGateConfig rsi_gate(const RsiLinkConfig& c, double period_s) {
  ControllerGateConfig g;
  g.sequence.bits = 64;
  g.sequence.max_ahead = c.ipoc_max_ahead_ms;
  g.sequence.restart_max = 0;
  g.sequence.confirm = c.confirm_jump;
  g.restart_silence_s = c.restart_silence_s;
  g.period_s = period_s;
  g.numbers_per_cycle = period_s * 1e3;
  g.stamp_bits = 64;
  return g;
}
const RsiLinkConfig& validated(const RsiLinkConfig& c) {
  c.validate();
  return c;
}
}  // namespace

RsiLink::RsiLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport,
                 const Clock& clock, ForceSource* force, const RsiLinkConfig& config)
    : comp_(compensator),
      strategy_(strategy),
      transport_(transport),
      clock_(clock),
      force_(force),
      config_(validated(config)),
      delay_(config.initial_delay_s),
      history_(config.history_cycles, compensator.model().dof()),
      gate_(rsi_gate(config, compensator.config().period_s)),
      ws_(compensator.model()),
      jac_(6, compensator.model().dof()) {
  const RobotModel& model = compensator.model();
  const int n = model.dof();
  // The tolerance allows for the controller's own rounding beyond its software limits.
  lower_ = model.lower_limits().array() - kPi / 180.0;
  upper_ = model.upper_limits().array() + kPi / 180.0;
  rx_.assign(config_.max_document_bytes + 1, 0);  // one byte more: an oversized datagram shows as such
  tx_.assign(kRsiMaxEncodedBytes, 0);
  for (RsiRobotMessage* m : {&msg_, &newest_}) m->actual_deg = m->setpoint_deg = JointVector::Zero(n);
  for (JointVector* q : {&input_.q_planned, &input_.q_feedback, &feedback_, &planned_, &previous_feedback_, &velocity_,
                         &target_, &command_, &no_distance_, &reply_.correction_deg}) {
    *q = JointVector::Zero(n);
  }
  last_ = history_.blank();
}

bool RsiLink::plausible(const RsiRobotMessage& m) const noexcept {
  for (int i = 0; i < lower_.size(); ++i) {
    const double actual = deg_to_rad(m.actual_deg[i]);
    if (!(actual >= lower_[i] && actual <= upper_[i])) return false;
    if (m.has_setpoint) {
      const double setpoint = deg_to_rad(m.setpoint_deg[i]);
      if (!(setpoint >= lower_[i] && setpoint <= upper_[i])) return false;
    }
  }
  return true;
}

RsiLink::Drain RsiLink::drain(double timeout_s, bool& restarted) noexcept {
  restarted = false;
  if (!transport_.wait_readable(timeout_s)) return Drain::kNothing;
  const int axes = comp_.model().dof();
  const double now = clock_.now_s();
  bool have = false;
  // Drain: only the newest usable document is answered (an older one's answer would be late anyway).
  for (int i = 0; i < 1024; ++i) {
    DatagramAddress from;
    const long n = transport_.receive(rx_.data(), rx_.size(), from);
    if (n < 0) break;
    ++counters_.datagrams;
    gate_.heard(from, now);  // the silence that ends a session counts from any datagram of the controller
    if (static_cast<std::size_t>(n) > config_.max_document_bytes) {
      ++counters_.oversized;
      continue;
    }
    switch (decode_rsi_robot(rx_.data(), static_cast<std::size_t>(n), axes, msg_)) {
      case RsiDecodeStatus::kOk: break;
      case RsiDecodeStatus::kMalformed: ++counters_.malformed; continue;
      case RsiDecodeStatus::kTruncated: ++counters_.truncated; continue;
      case RsiDecodeStatus::kMissingIpoc: ++counters_.missing_header; continue;
      case RsiDecodeStatus::kMissingAxes: ++counters_.missing_joints; continue;
      case RsiDecodeStatus::kNonFinite: ++counters_.non_finite; continue;
      case RsiDecodeStatus::kEmpty: ++counters_.empty; continue;
      case RsiDecodeStatus::kForeign: ++counters_.foreign_document; continue;
      case RsiDecodeStatus::kIpocOutOfRange: ++counters_.sequence_out_of_range; continue;
    }
    if (!plausible(msg_)) {
      ++counters_.out_of_limits;
      continue;
    }
    bool session_start = false;
    if (!gate_.take(from, msg_.ipoc, msg_.ipoc, now, counters_, session_start, msg_arrival_)) continue;
    restarted = restarted || session_start;
    if (have) ++counters_.superseded;
    std::swap(newest_, msg_);
    arrival_ = msg_arrival_;
    have = true;
  }
  return have ? Drain::kMessage : Drain::kNoneUsable;
}

LinkPollResult RsiLink::poll(double timeout_s) noexcept {
  bool restarted = false;
  const Drain got = drain(timeout_s, restarted);
  if (got == Drain::kNothing) return LinkPollResult::kIdle;
  if (got == Drain::kNoneUsable) return LinkPollResult::kRejected;
  const auto t_read = std::chrono::steady_clock::now();
  const double now = clock_.now_s();
  const RsiRobotMessage& m = newest_;
  for (int i = 0; i < feedback_.size(); ++i) {
    feedback_[i] = deg_to_rad(m.actual_deg[i]);
    planned_[i] = m.has_setpoint ? deg_to_rad(m.setpoint_deg[i]) : feedback_[i];
  }
  state_ = LinkState::kRunning;
  if (m.has_delay) counters_.controller_late = m.delay;
  if (restarted) {
    // A new RSI session: the controller's AXISCORR starts again from zero offset, so must deflex's
    // correction (it then ramps at the rate bound), or the first answer would step the arm.
    if (answered_once_) comp_.reset();
    have_previous_ = false;
  }

  // The axes' velocity and the controller's period from the actual axes and the link's clock.
  if (have_previous_) {
    const double dt = now - previous_t_s_;
    if (dt > 0.0) {
      velocity_ += 0.5 * ((feedback_ - previous_feedback_) / dt - velocity_);
      period_s_ = period_s_ > 0.0 ? period_s_ + 0.1 * (dt - period_s_) : dt;
    }
  } else {
    velocity_.setZero();
  }
  previous_feedback_ = feedback_;
  previous_t_s_ = now;
  have_previous_ = true;

  if (m.has_setpoint) delay_.record_reference(now, planned_);
  delay_.observe_feedback(now, feedback_);
  // The correction sent now reaches the axes after the measured delay and AXISCORR's own latency:
  // the predictive strategy evaluates it where the program will be by then.
  const double lead = delay_.delay_s() + config_.correction_latency_s;
  target_ = planned_;
  if (strategy_.kind() == StrategyKind::kPredictive) target_ += lead * velocity_;
  input_.t_s = now;
  input_.q_planned = target_;
  input_.q_feedback = feedback_;
  const StrategyStatus ss = strategy_.prepare(input_, feedback_, target_, lead, comp_.filter_delay_s());
  input_.hold_to_zero = input_.hold_to_zero || ss != StrategyStatus::kOk;
  const CycleOutput out = force_ != nullptr ? comp_.step(input_, *force_) : comp_.step(input_);

  LinkCycleRecord& r = last_;
  r.t_s = now;
  r.program_time_s = 0.0;
  r.sequence = m.ipoc;
  r.q_nominal = planned_;
  r.q_feedback = feedback_;
  r.dtheta = out.dtheta;
  r.wrench_base = out.wrench_base;
  r.wrench_measured_base = out.wrench_measured_base;
  r.status = out.status;
  r.replied = false;
  r.delay_s = delay_.delay_s();
  r.arrival = arrival_;
  r.rotation_uncorrected_rad = 0.0;
  if (out.status == CycleStatus::kForceFault || out.status == CycleStatus::kInvalidInput) fault_pending_ = true;
  LinkPollResult result = LinkPollResult::kNotAnswered;
  if (static_cast<int>(out.status) < 0) {
    ++counters_.invalid_cycles;
  } else {
    command_ = planned_ - out.dtheta;
    r.q_command = command_;
    jacobian(comp_.model(), ws_, target_, EndPoint::kTcp, jac_);
    const Vector3 tcp = -(jac_.topRows<3>() * out.dtheta);
    r.tcp_correction_m = tcp;
    // The last check before anything leaves deflex: every axis and the TCP within the bounds of
    // "no correction".
    const double joint_bound = comp_.config().max_joint_correction_rad * (1.0 + 1e-9) + 1e-12;
    const double tcp_bound = comp_.config().max_tcp_correction_m * (1.0 + 1e-9) + 1e-12;
    if (!out.dtheta.allFinite() || !tcp.allFinite() || out.dtheta.cwiseAbs().maxCoeff() > joint_bound ||
        tcp.norm() > tcp_bound) {
      ++counters_.guard_trips;
      fault_pending_ = true;
    } else {
      reply_.ipoc = m.ipoc;
      for (int i = 0; i < out.dtheta.size(); ++i) reply_.correction_deg[i] = rad_to_deg(-out.dtheta[i]);
      const std::size_t n = encode_rsi_sensor(config_.sentype, reply_, tx_.data(), tx_.size());
      if (n > 0 && transport_.send_to(tx_.data(), n, gate_.controller())) {
        ++counters_.replies;
        answered_once_ = true;
        r.replied = true;
        result = LinkPollResult::kAnswered;
      } else {
        ++counters_.send_errors;
      }
    }
  }
  r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count();
  history_.record(r);
  return result;
}

}  // namespace deflex
