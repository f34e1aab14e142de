// What every controller link shares (see controller_link.hpp).
#include "deflex/link/controller_link.hpp"

#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

const char* to_string(LinkState s) {
  switch (s) {
    case LinkState::kWaiting:
      return "waiting";
    case LinkState::kRunning:
      return "running";
    case LinkState::kFinished:
      return "finished";
    case LinkState::kRefused:
      return "refused";
    case LinkState::kStopped:
      return "stopped";
  }
  return "unknown";
}

const char* to_string(LinkStopCause c) {
  switch (c) {
    case LinkStopCause::kNone:
      return "not stopped";
    case LinkStopCause::kRequested:
      return "stop requested";
    case LinkStopCause::kEnded:
      return "session ended";
    case LinkStopCause::kProtocol:
      return "protocol error";
    case LinkStopCause::kSilent:
      return "controller silent";
    case LinkStopCause::kConnection:
      return "connection lost";
    case LinkStopCause::kController:
      return "controller stopped or faulted";
    case LinkStopCause::kSafety:
      return "safety guard";
    case LinkStopCause::kTooSlow:
      return "controller too slow";
  }
  return "unknown";
}

void LinkStopRules::validate() const {
  if (!std::isfinite(stop_silence_s) || !(stop_silence_s > 0.0) || stop_silence_s > 3600.0) {
    throw InputError(fmt::format("link: the stop silence must be > 0 s and <= 3600 s (got {})", stop_silence_s));
  }
  if (!std::isfinite(end_silence_s) || !(end_silence_s > 0.0) || end_silence_s > 3600.0) {
    throw InputError(fmt::format("link: the end silence must be > 0 s and <= 3600 s (got {})", end_silence_s));
  }
}

namespace {
const LinkStopRules& validated(const LinkStopRules& r) {
  r.validate();
  return r;
}
}  // namespace

ControllerLink::ControllerLink(OnlineCompensator& compensator, OnlineStrategy& strategy, const Clock& clock,
                               const CommandLimits& limits, const LinkStopRules& rules, std::size_t history_cycles)
    : cycle_(compensator, strategy, limits, history_cycles, counters_),
      clock_(clock),
      rules_(validated(rules)),
      last_message_s_(std::numeric_limits<double>::quiet_NaN()) {}

void ControllerLink::stop_link(LinkStopCause cause, const char* format, ...) noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) return;
  va_list args;
  va_start(args, format);
  std::vsnprintf(stop_reason_.data(), stop_reason_.size(), format, args);
  va_end(args);
  stop_cause_ = cause;
  state_ = LinkState::kStopped;
  announced_ = false;
}

void ControllerLink::refuse_start(const JointVector& distance) noexcept {
  start_distance_ = distance;
  state_ = LinkState::kRefused;
  ++counters_.refused;
  announced_ = false;
}

void ControllerLink::heard(double now) noexcept {
  after_silence_ = true;
  if (std::isfinite(last_message_s_)) {
    const double gap = now - last_message_s_;
    after_silence_ = gap > 2.0 * cycle_.compensator().config().period_s;
    if (after_silence_) {
      ++counters_.silences;
      counters_.longest_silence_s = std::max(counters_.longest_silence_s, gap);
    }
  }
  last_message_s_ = now;
}

bool ControllerLink::stop_if_anchor_unreachable(double gap, const char* what) noexcept {
  if (after_silence_ || gap <= 2.0) return false;
  stop_link(LinkStopCause::kController,
            "%s restarted without a silence, holding %.1f per-cycle step limits from deflex's last command: no command "
            "can be within the step limit of both, so the session was not resumed (restart it with the arm at rest)",
            what, gap);
  return true;
}

bool ControllerLink::apply_silence_rules(double now) noexcept {
  if ((state_ != LinkState::kRunning && state_ != LinkState::kFinished) || !std::isfinite(last_message_s_)) {
    return false;
  }
  const double silent = now - last_message_s_;
  // A stop ramp needs the controller to take its commands: one that fell silent meanwhile has nothing
  // to ramp (it holds its last reference or offset), so the planned stop ends there.
  if (ramping_down_ && silent > std::max(0.05, 10.0 * cycle_.compensator().config().period_s)) {
    stop_link(LinkStopCause::kRequested,
              "stopped on request: the controller fell silent for %.3f s during the stop ramp, so deflex stopped "
              "there",
              silent);
    return true;
  }
  if (state_ == LinkState::kFinished) {
    if (silent <= rules_.end_silence_s) return false;
    stop_link(LinkStopCause::kEnded, "the program ended and the controller went quiet (%.2f s): the session is over",
              silent);
    return true;
  }
  if (silent <= rules_.stop_silence_s) return false;
  if (silence_is_planned_end()) {
    stop_link(LinkStopCause::kEnded,
              "the controller went quiet for %.2f s after a healthy session (--end-on-silence): its program's end",
              silent);
  } else {
    stop_link(
        LinkStopCause::kSilent,
        "no usable message from the controller for %.2f s (the stop silence is %.2f s): it stopped or the network "
        "is down (%" PRIu64 " datagrams rejected in all)",
        silent, rules_.stop_silence_s, counters_.rejected());
  }
  return true;
}

void ControllerLink::request_planned_stop(double ramp_s) noexcept {
  if (ramping_down_ || state_ != LinkState::kRunning) {
    stop();
    return;
  }
  ramping_down_ = true;
  ramp_down_s_ = ramp_s;
}

void ControllerLink::stop_when_correction_gone() noexcept {
  if (!ramping_down_) return;
  ++ramp_cycles_;
  // What went on the wire: the TCP offset, or the joint offset (the correction's last cycle may be
  // zero while the step limit still holds the offset sent back).
  const bool gone = cycle_.limits().form == CommandForm::kTcpOffset
                        ? cycle_.tcp_offset_m().norm() == 0.0
                        : cycle_.joint_command().cwiseAbs().maxCoeff() == 0.0;
  if (!gone) return;
  stop_link(LinkStopCause::kRequested,
            "stopped on request: the correction ramped to zero at the rate bound over %llu cycles, then deflex "
            "stopped answering",
            static_cast<unsigned long long>(ramp_cycles_));
}

LinkPollResult ControllerLink::cycle_not_passed(LinkCycle::Verdict verdict, double compute_s) noexcept {
  cycle_.not_sent(compute_s);
  if (verdict != LinkCycle::Verdict::kGuard) return LinkPollResult::kNotAnswered;
  stop_link(LinkStopCause::kSafety, "%s", cycle_.guard_message());
  return announce_terminal();
}

LinkPollResult ControllerLink::announce_terminal() noexcept {
  if (announced_) return LinkPollResult::kIdle;
  announced_ = true;
  return state_ == LinkState::kRefused ? LinkPollResult::kRefused : LinkPollResult::kStopped;
}

}  // namespace deflex
