// KUKA RSI axis correction (see rsi_link.hpp).
#include "deflex/rsi/rsi_link.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

void RsiLinkConfig::validate() const {
  if (!valid_rsi_sentype(sentype)) {
    throw InputError(
        fmt::format("RSI link: SENTYPE '{}' must be 1..32 letters, digits, '_' or '-', starting with a "
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
  if (controller_timeout < 1 || controller_timeout > 1000000) {
    throw InputError("RSI link: the controller's Timeout must be 1..1000000 late answers");
  }
  stop.validate();
}

namespace {
// The IPOC is both the sequence number and the time stamp: milliseconds, growing by the period every
// cycle, never starting again from a small number. The drivers read it as an unsigned 64-bit number
// and no public source states the controller's own width, so both are taken: a 64-bit counter, and a
// 32-bit one across its wrap at 2^32 ms (49.7 days), which is the next cycle and not a restart.
ControllerGateConfig rsi_gate(const RsiLinkConfig& c, double period_s) {
  ControllerGateConfig g;
  g.sequence.bits = 64;
  g.sequence.wraps_at_32 = true;
  g.sequence.max_ahead = c.ipoc_max_ahead_ms;
  g.sequence.restart_max = 0;
  g.sequence.confirm = c.confirm_jump;
  g.restart_silence_s = c.restart_silence_s;
  g.period_s = period_s;
  g.numbers_per_cycle = period_s * 1e3;
  g.stamp_bits = 64;
  g.reorder_window = static_cast<std::uint64_t>(std::ceil(32.0 * period_s * 1e3));  // 32 cycles of IPOC
  return g;
}
const RsiLinkConfig& validated(const RsiLinkConfig& c) {
  c.validate();
  return c;
}
}  // namespace

namespace {
CommandLimits offset_limits(const OnlineCompensator& c) {
  CommandLimits l = command_limits(CommandForm::kJointOffset, c.config(), c.model().dof());
  l.rounding = WireRounding::kDecimalsDeg;  // the <AK> values: degrees with 6 decimals (rsi_xml.cpp)
  l.decimals = 6;
  return l;
}
}  // namespace

RsiLink::RsiLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport,
                 const Clock& clock, const RsiLinkConfig& config)
    : ControllerLink(compensator, strategy, clock, offset_limits(compensator), validated(config).stop,
                     config.history_cycles),
      transport_(transport),
      config_(config),
      delay_(config.initial_delay_s),
      gate_(rsi_gate(config, compensator.config().period_s)) {
  const RobotModel& model = compensator.model();
  const int n = model.dof();
  // The tolerance allows for the controller's own rounding beyond its software limits.
  lower_ = model.lower_limits().array() - kPi / 180.0;
  upper_ = model.upper_limits().array() + kPi / 180.0;
  rx_.assign(config_.max_document_bytes + 1, 0);  // one byte more: an oversized datagram shows as such
  tx_.assign(kRsiMaxEncodedBytes, 0);
  for (RsiRobotMessage* m : {&msg_, &newest_}) m->actual_deg = m->setpoint_deg = JointVector::Zero(n);
  for (JointVector* q : {&feedback_, &planned_, &reference_, &reply_.correction_deg}) {
    *q = JointVector::Zero(n);
  }
}

bool RsiLink::silence_is_planned_end() const {
  return rules_.end_on_silence &&
         counters_.controller_late + 1 < static_cast<std::uint64_t>(config_.controller_timeout);
}

bool RsiLink::timeout_reached(double now) noexcept {
  if (state_ != LinkState::kRunning || !std::isfinite(last_message_s())) return false;
  // The controller reported a late count one short of its Timeout, and the next cycle's document did
  // not come: its count reached the Timeout and RSI stopped. (Silence alone cannot tell RSI stopped on
  // its Timeout from RSI_OFF or a network outage: the stop silence rules decide those.)
  const double period = cycle_.compensator().config().period_s;
  if (now - last_message_s() < 2.0 * period) return false;
  if (counters_.controller_late + 1 < static_cast<std::uint64_t>(config_.controller_timeout)) return false;
  stop_link(LinkStopCause::kController,
            "RSI stopped: the controller's late count reached its Timeout of %d (its last <Delay> was %llu, and no "
            "document came for %.0f ms)",
            config_.controller_timeout, static_cast<unsigned long long>(counters_.controller_late),
            (now - last_message_s()) * 1e3);
  return true;
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
  const int axes = cycle_.compensator().model().dof();
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
      case RsiDecodeStatus::kOk:
        break;
      case RsiDecodeStatus::kMalformed:
        ++counters_.malformed;
        continue;
      case RsiDecodeStatus::kTruncated:
        ++counters_.truncated;
        continue;
      case RsiDecodeStatus::kMissingIpoc:
        ++counters_.missing_header;
        continue;
      case RsiDecodeStatus::kMissingAxes:
        ++counters_.missing_joints;
        continue;
      case RsiDecodeStatus::kNonFinite:
        ++counters_.non_finite;
        continue;
      case RsiDecodeStatus::kEmpty:
        ++counters_.empty;
        continue;
      case RsiDecodeStatus::kForeign:
        ++counters_.foreign_document;
        continue;
      case RsiDecodeStatus::kIpocOutOfRange:
        ++counters_.sequence_out_of_range;
        continue;
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
    receipt_age_s_ = transport_.since_receipt_s();
    taken_at_s_ = clock_.now_s();
    have = true;
  }
  return have ? Drain::kMessage : Drain::kNoneUsable;
}

std::string RsiLink::protocol_summary() const {
  return fmt::format("rsi: the controller counted {} answers late (its <Delay>; RSI stops at its Timeout of {})",
                     counters_.controller_late, config_.controller_timeout);
}

LinkPollResult RsiLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kStopped) {
    bool ignored = false;
    (void)drain(0.0, ignored);
    return announce_terminal();
  }
  bool restarted = false;
  const Drain got = drain(timeout_s, restarted);
  const double now = clock_.now_s();
  if (got != Drain::kMessage) {
    if (timeout_reached(now) || apply_silence_rules(now)) return announce_terminal();
    return got == Drain::kNothing ? LinkPollResult::kIdle : LinkPollResult::kRejected;
  }
  const auto t_read = std::chrono::steady_clock::now();
  const RsiRobotMessage& m = newest_;
  for (int i = 0; i < feedback_.size(); ++i) {
    feedback_[i] = deg_to_rad(m.actual_deg[i]);
    planned_[i] = m.has_setpoint ? deg_to_rad(m.setpoint_deg[i]) : feedback_[i];
  }
  heard(now);
  if (m.has_delay) counters_.controller_late = m.delay;
  const bool session_start = restarted || state_ == LinkState::kWaiting;
  if (session_start) {
    // A new RSI session: the controller's AXISCORR starts again from zero offset, so must deflex's
    // correction (it then ramps at the rate bound), or the first answer would step the arm. Without a
    // silence before it the controller may still apply the last offset sent: the next must step from both.
    if (stop_if_anchor_unreachable(cycle_.reanchor_gap(JointVector(JointVector::Zero(feedback_.size()))), "RSI")) {
      return announce_terminal();
    }
    cycle_.restart_from_zero(after_silence());
    cycle_.motion().restart();
    state_ = LinkState::kRunning;
  }

  // The axes' velocity and the controller's period from the actual axes and the link's clock.
  (void)cycle_.motion().observe(now, feedback_);
  // The axes follow ASPos plus the offset AXISCORR applies (the last one answered, which the cycle
  // keeps as its step reference: zero from a restart): that sum is what the feedback shows after the
  // delay. ASPos alone would be off the feedback by the correction.
  if (m.has_setpoint) {
    reference_ = planned_ + cycle_.last_command();
    delay_.record_reference(now, reference_);
  }
  delay_.observe_feedback(now, feedback_);
  return answer(m, now, session_start, t_read);
}

// The cycle for this message, and the answer: the whole AKorr offset, in degrees.
LinkPollResult RsiLink::answer(const RsiRobotMessage& m, double now, bool session_start,
                               std::chrono::steady_clock::time_point t_read) noexcept {
  // The correction sent now reaches the axes after the measured delay and AXISCORR's own latency:
  // the predictive strategy evaluates it where the program will be by then.
  const double lead = delay_.delay_s() + config_.correction_latency_s;
  CycleRequest rq;
  rq.t_s = now;
  rq.sequence = m.ipoc;
  rq.nominal = &planned_;
  rq.feedback = &feedback_;
  rq.target = &cycle_.lead_target(planned_, lead);
  rq.delay_s = delay_.delay_s();
  rq.lead_s = lead;
  rq.session_start = session_start;
  rq.hold = ramping_down_;  // a planned stop ramps the correction out
  rq.arrival = arrival_;
  const LinkCycle::Verdict verdict = cycle_.run(rq);
  const auto compute = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count(); };
  if (verdict != LinkCycle::Verdict::kSend) return cycle_not_passed(verdict, compute());
  reply_.ipoc = m.ipoc;
  const JointVector& ak = cycle_.joint_command();  // the whole offset, rounded as the answer carries it
  for (int i = 0; i < ak.size(); ++i) reply_.correction_deg[i] = rad_to_deg(ak[i]);
  const std::size_t n = encode_rsi_sensor(config_.sentype, reply_, tx_.data(), tx_.size());
  if (n == 0 || !transport_.send_to(tx_.data(), n, gate_.controller())) {
    ++counters_.send_errors;
    cycle_.not_sent(compute());
    return LinkPollResult::kNotAnswered;
  }
  ++counters_.replies;
  cycle_.sent(compute(), receipt_age_s_ + (clock_.now_s() - taken_at_s_));
  stop_when_correction_gone();
  return LinkPollResult::kAnswered;
}

}  // namespace deflex
