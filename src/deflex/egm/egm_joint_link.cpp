// ABB EGM position guidance, joint mode (see egm_joint_link.hpp).
#include "deflex/egm/egm_joint_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

namespace {

const char* mci_name(int state) {
  switch (state) {
    case 1:
      return "ERROR";
    case 2:
      return "STOPPED";
    case 3:
      return "RUNNING";
    default:
      return "UNDEFINED";
  }
}

CommandLimits joint_limits(const OnlineCompensator& c, const JointTrajectory* program, const JointStreamConfig& s) {
  if (program == nullptr) throw InputError("EGM joint link: no program to stream");
  if (program->dof() != c.model().dof()) {
    throw InputError(
        fmt::format("EGM joint link: the program has {} joints, the robot {}", program->dof(), c.model().dof()));
  }
  return command_limits(CommandForm::kJointTarget, c.config(), c.model().dof(), program, &s);
}

}  // namespace

EgmJointLink::EgmJointLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                           std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport,
                           const Clock& clock, const EgmJointLinkConfig& config)
    : ControllerLink(compensator, strategy, clock, joint_limits(compensator, nominal.get(), config.stream), config.stop,
                     config.history_cycles),
      config_(config),
      receiver_(transport, clock, compensator.model(), with_period(config.receiver, compensator.config().period_s),
                counters_),
      stream_(std::move(nominal), config.stream),
      delay_(config.initial_delay_s),
      period_s_(compensator.config().period_s) {
  const int n = compensator.model().dof();
  for (JointVector* q : {&feedback_, &planned_, &program_, &program_velocity_, &blend_, &blend_velocity_, &nominal_,
                         &reply_.planned_joints_deg}) {
    *q = JointVector::Zero(n);
  }
  reply_.speed_ref_joints_deg_s = config_.send_speed_reference ? JointVector::Zero(n) : JointVector();
  tx_.assign(1024, 0);
}

bool EgmJointLink::controller_state(const EgmRobotMessage& m) noexcept {
  if (m.motor_state == 2) {
    stop_link(LinkStopCause::kController,
              "the controller reports its motors off (EgmRobot motorState OFF: an emergency or protective stop) at "
              "program time %.3f s",
              stream_.program_time_s() - stream_.trajectory().start_time_s());
    return false;
  }
  if (m.mci_state == 3) {
    egm_ran_ = true;
  } else if (m.mci_state == 1 || m.mci_state == 2) {
    if (!egm_ran_) {
      // EGM streams (EGMStreamStart) but does not move yet: nothing is consumed, the program waits.
      ++counters_.not_running;
      return false;
    }
    if (stream_.finished() && m.mci_state == 2) {
      stop_link(LinkStopCause::kEnded, "the controller ended EGM (mciState STOPPED) after the program's end");
    } else {
      stop_link(LinkStopCause::kController,
                "the controller ended EGM (mciState %s) at program time %.3f s of %.3f s, before the program's end",
                mci_name(m.mci_state), stream_.program_time_s() - stream_.trajectory().start_time_s(),
                stream_.trajectory().duration_s());
    }
    return false;
  }
  return true;
}

// A session (the first message, a restart) starts from the reference the controller holds. A
// controller that kept following deflex's stream reports one of its last commands: the stream goes
// on from the last one sent, as if nothing happened. One that reset its reference (a new EGMRunJoint)
// reports where it now is: after a silence (its previous session ended) the stream goes on from there;
// without one it may still be following the last command sent, and a reference more than two step
// limits from it leaves no command that steps from both: the session is not resumed.
// False: the session is not started (the link refused or stopped; poll() announces it).
bool EgmJointLink::begin_session() noexcept {
  const JointVector* anchor = &planned_;
  const double gap = cycle_.reanchor_gap(planned_);
  if (cycle_.has_sent() && gap <= 2.0) anchor = &cycle_.last_command();
  if (stop_if_anchor_unreachable(gap, "the controller (EGM)")) return false;
  nominal_ = *anchor;  // begin() and anchor_joints() must not see the cycle's own buffer change
  if (!stream_.begin(nominal_, cycle_.correction())) {
    if (state_ == LinkState::kWaiting) {
      refuse_start(stream_.distance());
    } else {
      Eigen::Index j = 0;
      const double d = stream_.distance().maxCoeff(&j);
      stop_link(LinkStopCause::kController,
                "the controller restarted holding joint %d %.3f deg from deflex's command (tolerance %.3f deg): not "
                "resumed",
                static_cast<int>(j) + 1, rad_to_deg(d), rad_to_deg(config_.stream.start_tolerance_rad));
    }
    return false;
  }
  cycle_.anchor_joints(nominal_, after_silence());
  if (state_ == LinkState::kWaiting || state_ == LinkState::kRunning) state_ = LinkState::kRunning;
  return true;
}

LinkPollResult EgmJointLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) {
    bool ignored = false;
    if (receiver_.drain(0.0, ignored) == EgmReceiver::Result::kMessage && state_ == LinkState::kRefused) {
      ++counters_.refused;
    }
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
    planned_[i] = m.has_planned ? deg_to_rad(m.planned_joints_deg[i]) : feedback_[i];
  }
  heard(now);
  if (!controller_state(m)) {
    return state_ == LinkState::kStopped ? announce_terminal() : LinkPollResult::kNotAnswered;
  }

  const bool session_start = restarted || state_ == LinkState::kWaiting;
  if (session_start && !begin_session()) return announce_terminal();
  if (ramping_down_) stream_.begin_stop(ramp_down_s_);
  stream_.sample(program_, program_velocity_, blend_, blend_velocity_);
  nominal_ = program_ + blend_;

  delay_.observe_feedback(now, feedback_);
  CycleRequest rq;
  rq.t_s = now;
  rq.sequence = m.seqno;
  rq.program_time_s = stream_.program_time_s();
  rq.nominal = &program_;
  rq.blend = &blend_;
  rq.feedback = &feedback_;
  rq.target = &nominal_;
  rq.delay_s = rq.lead_s = delay_.delay_s();
  rq.session_start = session_start;
  rq.arrival = receiver_.arrival();
  const LinkCycle::Verdict verdict = cycle_.run(rq);
  const auto compute = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count(); };
  if (verdict != LinkCycle::Verdict::kSend) return cycle_not_passed(verdict, compute());
  return send(now, cycle_.joint_command(), t_read);
}

// The joint target (and its speed) to the controller; then the stream moves on.
LinkPollResult EgmJointLink::send(double now, const JointVector& command,
                                  std::chrono::steady_clock::time_point t_read) noexcept {
  const auto compute_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count();
  };
  reply_.seqno = ++reply_seq_;
  reply_.tm_ms = egm_time_stamp_ms(now);
  for (int i = 0; i < command.size(); ++i) {
    reply_.planned_joints_deg[i] = rad_to_deg(command[i]);
    if (config_.send_speed_reference) {
      // The target's own velocity: the program's and the blend's, less the correction's change this
      // cycle (the controller's position loop alone would follow a moving target late).
      const double correction_rate = (cycle_.output().dtheta[i] - cycle_.correction()[i]) / period_s_;
      reply_.speed_ref_joints_deg_s[i] = rad_to_deg(program_velocity_[i] + blend_velocity_[i] - correction_rate);
    }
  }
  const std::size_t n = receiver_.codec().encode_sensor(reply_, tx_.data(), tx_.size());
  if (n == 0) ++counters_.send_errors;
  if (n == 0 || !receiver_.reply(tx_.data(), n)) {
    cycle_.not_sent(compute_s());
    return LinkPollResult::kNotAnswered;
  }
  cycle_.sent(compute_s(), receiver_.answer_time_s(clock_.now_s()));
  delay_.record_reference(now, command);
  stream_.consumed(period_s_);
  if (ramping_down_ && stream_.at_standstill()) {
    stop_link(LinkStopCause::kRequested,
              "stopped on request: the program was brought to a standstill on its path over %.2f s, at program time "
              "%.3f s; deflex then stopped answering (the controller holds its last reference until its EGM "
              "times out)",
              ramp_down_s_, stream_.program_time_s() - stream_.trajectory().start_time_s());
    return LinkPollResult::kAnswered;
  }
  if (stream_.finished() && state_ == LinkState::kRunning) state_ = LinkState::kFinished;
  return LinkPollResult::kAnswered;
}

}  // namespace deflex
