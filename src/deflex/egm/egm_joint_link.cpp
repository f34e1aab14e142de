// ABB EGM position guidance, joint mode (see egm_joint_link.hpp).
#include "deflex/egm/egm_joint_link.hpp"

#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

EgmJointLink::EgmJointLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                           std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport,
                           const Clock& clock, ForceSource* force, const EgmJointLinkConfig& config)
    : comp_(compensator),
      strategy_(strategy),
      clock_(clock),
      force_(force),
      config_(config),
      receiver_(transport, clock, compensator.model(), with_period(config.receiver, compensator.config().period_s),
                counters_),
      stream_(nominal, config.stream),
      delay_(config.initial_delay_s),
      history_(config.history_cycles, compensator.model().dof()) {
  const int n = compensator.model().dof();
  if (nominal->dof() != n) {
    throw InputError(fmt::format("EGM joint link: the program has {} joints, the robot {}", nominal->dof(), n));
  }
  for (JointVector* q : {&input_.q_planned, &input_.q_feedback, &nominal_, &nominal_velocity_, &feedback_, &command_,
                         &previous_dtheta_, &reply_.planned_joints_deg}) {
    *q = JointVector::Zero(n);
  }
  reply_.speed_ref_joints_deg_s = config_.send_speed_reference ? JointVector::Zero(n) : JointVector();
  tx_.assign(1024, 0);
  last_ = history_.blank();
}

LinkPollResult EgmJointLink::poll(double timeout_s) noexcept {
  bool restarted = false;
  const EgmReceiver::Result got = receiver_.drain(timeout_s, restarted);
  if (got == EgmReceiver::Result::kNothing) return LinkPollResult::kIdle;
  if (got == EgmReceiver::Result::kNoneUsable) return LinkPollResult::kRejected;
  const auto t_read = std::chrono::steady_clock::now();
  const double now = clock_.now_s();
  const EgmRobotMessage& m = receiver_.message();
  for (int i = 0; i < feedback_.size(); ++i) feedback_[i] = deg_to_rad(m.feedback_joints_deg[i]);

  if (state_ == LinkState::kRefused) {
    ++counters_.refused;
    return LinkPollResult::kRefused;
  }
  // A new session (the first message, or the first after a silence) must find the arm where the
  // program is; otherwise nothing is ever sent.
  if (restarted || stream_.paused_at(now) || state_ == LinkState::kWaiting) {
    if (!stream_.begin(now, feedback_)) {
      state_ = LinkState::kRefused;
      ++counters_.refused;
      fault_pending_ = true;
      return LinkPollResult::kRefused;
    }
    state_ = LinkState::kRunning;
  }
  stream_.advance(now, nominal_, nominal_velocity_);
  if (stream_.finished()) state_ = LinkState::kFinished;

  delay_.observe_feedback(now, feedback_);
  input_.t_s = now;
  input_.q_planned = nominal_;
  input_.q_feedback = feedback_;
  const StrategyStatus ss =
      strategy_.prepare(input_, feedback_, nominal_, delay_.delay_s(), comp_.filter_delay_s());
  input_.hold_to_zero = input_.hold_to_zero || ss != StrategyStatus::kOk;
  const CycleOutput out = force_ != nullptr ? comp_.step(input_, *force_) : comp_.step(input_);

  LinkCycleRecord& r = last_;
  r.t_s = now;
  r.program_time_s = stream_.program_time_s();
  r.sequence = m.seqno;
  r.q_nominal = nominal_;
  r.q_feedback = feedback_;
  r.dtheta = out.dtheta;
  r.wrench_base = out.wrench_base;
  r.wrench_measured_base = out.wrench_measured_base;
  r.status = out.status;
  r.replied = false;
  r.delay_s = delay_.delay_s();
  r.arrival = receiver_.arrival();
  r.rotation_uncorrected_rad = 0.0;
  if (out.status == CycleStatus::kForceFault || out.status == CycleStatus::kInvalidInput) {
    fault_pending_ = true;
  }
  LinkPollResult result = LinkPollResult::kNotAnswered;
  if (static_cast<int>(out.status) < 0) {
    ++counters_.invalid_cycles;
  } else {
    command_ = nominal_ - out.dtheta;
    r.q_command = command_;
    r.tcp_correction_m = -out.tcp_deflection_base_m;  // what the correction moves the TCP by
    // The last check before anything leaves deflex: every joint within the bound of the nominal.
    const double bound = comp_.config().max_joint_correction_rad * (1.0 + 1e-9) + 1e-12;
    if (!command_.allFinite() || (command_ - nominal_).cwiseAbs().maxCoeff() > bound) {
      ++counters_.guard_trips;
      fault_pending_ = true;
    } else {
      reply_.seqno = ++reply_seq_;
      reply_.tm_ms = egm_time_stamp_ms(now);
      // The speed reference is the target's own velocity: the nominal's, less the correction's change
      // (the controller's position loop alone would follow a moving correction late).
      const double dt = now - previous_reply_s_;
      const bool have_rate = have_previous_reply_ && dt > 0.0 && dt < 0.1;
      for (int i = 0; i < command_.size(); ++i) {
        reply_.planned_joints_deg[i] = rad_to_deg(command_[i]);
        if (config_.send_speed_reference) {
          const double correction_rate = have_rate ? (out.dtheta[i] - previous_dtheta_[i]) / dt : 0.0;
          reply_.speed_ref_joints_deg_s[i] = rad_to_deg(nominal_velocity_[i] - correction_rate);
        }
      }
      previous_dtheta_ = out.dtheta;
      previous_reply_s_ = now;
      have_previous_reply_ = true;
      const std::size_t n = receiver_.codec().encode_sensor(reply_, tx_.data(), tx_.size());
      if (n > 0 && receiver_.reply(tx_.data(), n)) {
        r.replied = true;
        result = LinkPollResult::kAnswered;
        delay_.record_reference(now, command_);
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
