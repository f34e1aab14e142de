// Yaskawa MotoROS2 real-time motion, deflex as the motion source (see motoros2_rt_link.hpp).
#include "deflex/motoros2/motoros2_rt_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

namespace rt = motoros2_rt;

// A reply's command position further than this from what deflex's increment should have made it is a
// shortfall (lost, purged or truncated motion). The controller counts in pulses and reports radians
// converted from them: a few pulses of rounding stay below it (its own truncation flag fires at 20).
constexpr double kShortfallRad = 0.001 * kPi / 180.0;

CommandLimits motoros2_limits(const OnlineCompensator& c, const JointTrajectory* program,
                              const Motoros2RtLinkConfig& m) {
  m.validate();
  if (program == nullptr) throw InputError("MotoROS2 real-time link: no program to stream");
  if (program->dof() != c.model().dof()) {
    throw InputError(fmt::format("MotoROS2 real-time link: the program has {} joints, the robot {}", program->dof(),
                                 c.model().dof()));
  }
  if (c.model().dof() > static_cast<int>(rt::kAxesPerGroup)) {
    throw InputError(fmt::format("MotoROS2 real-time link: the robot has {} joints, a control group at most {}",
                                 c.model().dof(), rt::kAxesPerGroup));
  }
  return command_limits(CommandForm::kJointTarget, c.config(), c.model().dof(), program, &m.stream);
}

}  // namespace

void Motoros2RtLinkConfig::validate() const {
  stream.validate();
  stop.validate();
  if (group < 0 || group >= static_cast<int>(rt::kGroups)) {
    throw InputError(fmt::format("setting motoros2 group (--motoros2-group): must be 0..7 (got {})", group));
  }
  if (tool < 0 || tool > 63) {
    throw InputError(fmt::format("setting motoros2 tool (--motoros2-tool): must be 0..63 (got {})", tool));
  }
  if (!std::isfinite(resend_after_s) || !(resend_after_s > 0.0) || resend_after_s > 1.0) {
    throw InputError(
        fmt::format("setting motoros2 resend (--motoros2-resend-ms): must be > 0 and <= 1000 ms (got {:g} ms)",
                    resend_after_s * 1e3));
  }
  if (max_truncation_run < 0 || max_truncation_run > 100000) {
    throw InputError(
        fmt::format("setting motoros2 truncation run (--motoros2-max-truncations): must be 0..100000 (got {})",
                    max_truncation_run));
  }
  if (status_port < -1 || status_port > 65535) {
    throw InputError(fmt::format(
        "setting motoros2 status port (--motoros2-status-port): 1..65535, or -1 for none (got {})", status_port));
  }
  if (max_packet_bytes < rt::kReplyBytes) {
    throw InputError(fmt::format("setting motoros2 max_packet_bytes: must be at least the reply's {} bytes (got {})",
                                 rt::kReplyBytes, max_packet_bytes));
  }
}

Motoros2RtLink::Motoros2RtLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                               std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport,
                               const Clock& clock, const Motoros2RtLinkConfig& config, DatagramTransport* status)
    : ControllerLink(compensator, strategy, clock, motoros2_limits(compensator, nominal.get(), config), config.stop,
                     config.history_cycles),
      config_(config),
      transport_(transport),
      status_(status),
      stream_(std::move(nominal), config.stream),
      delay_(config.initial_delay_s),
      period_s_(compensator.config().period_s) {
  const int n = compensator.model().dof();
  for (JointVector* q : {&feedback_, &reported_, &expected_, &increment_, &program_, &program_velocity_, &blend_,
                         &blend_velocity_, &nominal_}) {
    *q = JointVector::Zero(n);
  }
  rx_.assign(config_.max_packet_bytes + 1, 0);
  tx_.assign(rt::kCommandBytes, 0);
  encoded_.assign(rt::kCommandBytes, 0);
  command_.kind = rt::IncrementKind::kJoint;
  command_.tool[static_cast<std::size_t>(config_.group)] = config_.tool;
}

// Encodes the command into a scratch buffer and sends it; only a command that went out replaces the
// one a resend repeats.
bool Motoros2RtLink::send(std::uint32_t sequence, const JointVector& increment) noexcept {
  command_.sequence = sequence;
  auto& delta = command_.delta[static_cast<std::size_t>(config_.group)];
  delta.fill(0.0);
  for (int i = 0; i < increment.size(); ++i) delta[static_cast<std::size_t>(i)] = increment[i];
  const std::size_t n = rt::encode(command_, encoded_.data(), encoded_.size());
  if (n == 0 || !transport_.send_to(encoded_.data(), n, config_.controller)) {
    ++counters_.send_errors;
    return false;
  }
  std::swap(tx_, encoded_);  // no allocation: the two buffers trade places
  tx_size_ = n;
  sent_any_ = true;
  last_send_s_ = clock_.now_s();
  ++counters_.replies;
  return true;
}

void Motoros2RtLink::resend_if_due(double now) noexcept {
  if (!sent_any_ || now - last_send_s_ < config_.resend_after_s) return;
  last_send_s_ = now;
  if (!transport_.send_to(tx_.data(), tx_size_, config_.controller)) {
    ++counters_.send_errors;
    return;
  }
  ++resent_;
}

// One datagram: true when it is the reply to the outstanding command (copied into reply_).
bool Motoros2RtLink::take(const unsigned char* data, long n, const DatagramAddress& from) noexcept {
  if (!(from == config_.controller)) {
    ++counters_.foreign_sender;
    return false;
  }
  if (n == 0) {
    ++counters_.empty;
    return false;
  }
  if (static_cast<std::size_t>(n) > config_.max_packet_bytes) {
    ++counters_.oversized;
    return false;
  }
  const rt::DecodeStatus d = rt::decode(data, static_cast<std::size_t>(n), scratch_);
  if (d != rt::DecodeStatus::kOk) {
    if (d == rt::DecodeStatus::kNonFinite) {
      ++counters_.non_finite;
    } else if (d == rt::DecodeStatus::kWrongSize) {
      ++(static_cast<std::size_t>(n) < rt::kReplyBytes ? counters_.truncated : counters_.oversized);
    } else {
      ++counters_.malformed;
    }
    return false;
  }
  const std::int32_t ahead = rt::sequence_ahead(outstanding_, scratch_.sequence_echo);
  if (ahead < 0) {
    ++counters_.duplicate;  // the reply to an earlier command (a resend's second answer, or overtaken)
    return false;
  }
  if (ahead > 0) {
    ++counters_.far_ahead;  // a number deflex never sent
    return false;
  }
  return true;
}

bool Motoros2RtLink::receive_reply(double timeout_s) noexcept {
  if (!transport_.wait_readable(timeout_s)) return false;
  bool got = false;
  DatagramAddress from;
  for (int i = 0; i < 1024; ++i) {  // a flood cannot hold the cycle
    const long n = transport_.receive(rx_.data(), rx_.size(), from);
    if (n < 0) break;
    ++counters_.datagrams;
    if (!take(rx_.data(), n, from)) continue;
    if (got) {
      ++counters_.duplicate;  // the same reply twice (the controller answered a resend too)
      continue;
    }
    reply_ = scratch_;
    receipt_age_s_ = transport_.since_receipt_s();
    taken_at_s_ = clock_.now_s();
    got = true;
  }
  return got;
}

// The reply's joints of deflex's group, and its truncation flag counted; false when the run of flags
// stopped the link.
bool Motoros2RtLink::read_reply() noexcept {
  const auto g = static_cast<std::size_t>(config_.group);
  for (int i = 0; i < feedback_.size(); ++i) {
    feedback_[i] = reply_.feedback_joints[g][static_cast<std::size_t>(i)];
    reported_[i] = reply_.command_joints[g][static_cast<std::size_t>(i)];
  }
  if (!reply_.fsu_truncated) {
    truncation_run_ = 0;
    return true;
  }
  ++truncations_;
  if (++truncation_run_ > config_.max_truncation_run) {
    stop_link(LinkStopCause::kController,
              "the controller's Functional Safety Unit truncated %d increments in a row (%.0f ms) at program time "
              "%.3f s: the program and its correction are faster than its speed limit lets the arm go (more than "
              "--motoros2-max-truncations %d); slow the program down or raise the FSU speed limit",
              truncation_run_, truncation_run_ * period_s_ * 1e3,
              stream_.program_time_s() - stream_.trajectory().start_time_s(), config_.max_truncation_run);
    return false;
  }
  return true;
}

// The status side channel, drained: false when a status stopped the link. The controller sends it from
// another port than its replies': its address is taken by IP alone.
bool Motoros2RtLink::read_status() noexcept {
  if (status_ == nullptr) return true;
  DatagramAddress from;
  for (int i = 0; i < 64; ++i) {
    const long n = status_->receive(rx_.data(), rx_.size(), from);
    if (n < 0) break;
    rt::RobotState s;
    if (from.ipv4 != config_.controller.ipv4 ||
        rt::decode(rx_.data(), static_cast<std::size_t>(n), s) != rt::DecodeStatus::kOk) {
      ++statuses_refused_;
      continue;
    }
    ++statuses_;
    const char* what = s.e_stopped          ? "an emergency stop"
                       : s.error            ? "an error"
                       : !s.drives_powered  ? "its drives off"
                       : !s.motion_possible ? "motion not possible"
                                            : nullptr;
    if (what != nullptr) {
      stop_link(LinkStopCause::kController,
                "the controller's status reports %s (error code %d) at program time %.3f s: it will not take the "
                "stream; clear it (reset_error) and start the real-time mode again",
                what, static_cast<int>(s.error_code), stream_.program_time_s() - stream_.trajectory().start_time_s());
      return false;
    }
  }
  return true;
}

LinkPollResult Motoros2RtLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) {
    const std::uint64_t before = counters_.datagrams;
    (void)receive_reply(0.0);
    if (state_ == LinkState::kRefused && counters_.datagrams > before) ++counters_.refused;
    return announce_terminal();
  }
  if (!read_status()) return announce_terminal();
  double now = clock_.now_s();
  if (!sent_any_) {
    // Command 0, no motion: its reply says where the controller's command position is.
    increment_.setZero();
    if (!send(0, increment_)) return LinkPollResult::kNotAnswered;
    outstanding_ = 0;
  }
  // The wait ends when the command outstanding is due again; a reply already queued is read first.
  const double wait_s = std::clamp(last_send_s_ + config_.resend_after_s - now, 0.0, std::max(0.0, timeout_s));
  const std::uint64_t before = counters_.datagrams;
  if (!receive_reply(wait_s)) {
    now = clock_.now_s();
    if (apply_silence_rules(now)) return announce_terminal();
    resend_if_due(now);
    return counters_.datagrams > before ? LinkPollResult::kRejected : LinkPollResult::kIdle;
  }
  now = clock_.now_s();
  heard(now);
  if (!read_reply()) return announce_terminal();
  if (state_ == LinkState::kWaiting) return start_session();
  if (state_ == LinkState::kFinished) return finish();
  return answer(now);
}

// The reply to command 0: the controller's command position is the anchor of the stream.
LinkPollResult Motoros2RtLink::start_session() noexcept {
  if (!stream_.begin(reported_, cycle_.correction())) {
    refuse_start(stream_.distance());
    return announce_terminal();
  }
  expected_ = reported_;
  state_ = LinkState::kRunning;
  return answer(taken_at_s_);
}

LinkPollResult Motoros2RtLink::answer(double now) noexcept {
  const auto t_read = std::chrono::steady_clock::now();
  const auto compute = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count(); };
  if ((reported_ - expected_).cwiseAbs().maxCoeff() > kShortfallRad) ++shortfalls_;
  // The step limit and the guard measure the increment from what the controller holds, not from what
  // deflex asked for.
  cycle_.anchor_joints(reported_, true);
  delay_.observe_feedback(now, feedback_);
  if (ramping_down_) stream_.begin_stop(ramp_down_s_);
  stream_.sample(program_, program_velocity_, blend_, blend_velocity_);
  nominal_ = program_ + blend_;
  CycleRequest rq;
  rq.t_s = now;
  rq.sequence = outstanding_ + 1U;
  rq.program_time_s = stream_.program_time_s();
  rq.nominal = &program_;
  rq.blend = &blend_;
  rq.feedback = &feedback_;
  rq.target = &nominal_;
  rq.delay_s = rq.lead_s = delay_.delay_s();
  rq.session_start = outstanding_ == 0;
  const LinkCycle::Verdict verdict = cycle_.run(rq);
  // Not answered: the command outstanding is sent again after resend_after_s and the controller's
  // answer to it (no motion) gives the next try.
  if (verdict != LinkCycle::Verdict::kSend) return cycle_not_passed(verdict, compute());
  // The program's end (or a planned stop at rest) sampled: the reply to this last increment ends the
  // session.
  const bool last = (ramping_down_ && stream_.at_standstill()) || stream_.finished();
  const JointVector& command = cycle_.joint_command();
  increment_ = command - reported_;
  if (!send(outstanding_ + 1U, increment_)) {
    cycle_.not_sent(compute());
    return LinkPollResult::kNotAnswered;
  }
  ++outstanding_;
  expected_ = reported_ + increment_;
  cycle_.sent(compute(), receipt_age_s_ + (clock_.now_s() - taken_at_s_));
  delay_.record_reference(now, command);
  stream_.consumed(period_s_);
  if (last) state_ = LinkState::kFinished;
  return LinkPollResult::kAnswered;
}

LinkPollResult Motoros2RtLink::finish() noexcept {
  if ((reported_ - expected_).cwiseAbs().maxCoeff() > kShortfallRad) ++shortfalls_;
  if (ramping_down_) {
    stop_link(LinkStopCause::kRequested,
              "stopped on request: the program was brought to rest on its path over %.2f s; the controller holds the "
              "arm and ends its real-time session after its timeout_for_rt_msg (or at stop_traj_mode)",
              ramp_down_s_);
  } else {
    stop_link(LinkStopCause::kEnded,
              "the program ended: the controller took its last increment and holds the arm; it ends its real-time "
              "session after its timeout_for_rt_msg (or at stop_traj_mode)");
  }
  return announce_terminal();
}

void Motoros2RtLink::stop() noexcept {
  stop_link(LinkStopCause::kRequested,
            "stop requested: no more increments went out; the arm stops where the last one took it and the "
            "controller ends its real-time session after its timeout_for_rt_msg");
}

std::string Motoros2RtLink::protocol_summary() const {
  return fmt::format(
      "MotoROS2 real-time (group {}): {} commands sent, {} sent again for a late reply; {} replies flagged an "
      "increment the safety unit truncated, {} found the controller's command position short of deflex's",
      config_.group, counters_.replies, resent_, truncations_, shortfalls_);
}

}  // namespace deflex
