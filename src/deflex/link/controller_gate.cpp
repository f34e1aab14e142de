// Which of a link's messages may be taken (see controller_gate.hpp).
#include "deflex/link/controller_gate.hpp"

#include <algorithm>
#include <cmath>

#include "deflex/text/errors.hpp"

namespace deflex {

void ControllerGateConfig::validate() const {
  sequence.validate();
  if (!std::isfinite(restart_silence_s) || !(restart_silence_s > 0.0)) {
    throw InputError("controller link: the restart silence must be > 0 s");
  }
  if (!std::isfinite(numbers_per_cycle) || !(numbers_per_cycle > 0.0)) {
    throw InputError("controller link: numbers_per_cycle must be > 0");
  }
  if (stamp_bits != 32 && stamp_bits != 64) throw InputError("controller link: time stamps are 32 or 64 bits wide");
}

namespace {
const ControllerGateConfig& validated(const ControllerGateConfig& c) {
  c.validate();
  return c;
}
}  // namespace

ControllerGate::ControllerGate(const ControllerGateConfig& config)
    : config_(validated(config)), sequence_(config.sequence), timing_(config.period_s) {}

void ControllerGate::heard(const DatagramAddress& from, double now_s) noexcept {
  if (!have_sender_) return;
  if (now_s - last_heard_s_ > config_.restart_silence_s) resync_ = true;
  if (from == sender_) last_heard_s_ = now_s;
}

std::int64_t ControllerGate::stamp_step_ms(std::uint64_t stamp_ms) const noexcept {
  SequenceRules stamps;
  stamps.bits = config_.stamp_bits;
  stamps.wraps_at_32 = config_.sequence.wraps_at_32;
  return SequenceTracker::distance(stamps, last_stamp_ms_, stamp_ms);
}

bool ControllerGate::take(const DatagramAddress& from, std::uint64_t number, std::uint64_t stamp_ms, double now_s,
                          LinkCounters& counters, bool& session_start, LinkArrival& arrival) noexcept {
  // One controller owns the link; another sender may take over only after the controller fell silent.
  if (have_sender_ && !(from == sender_) && !resync_) {
    ++counters.foreign_sender;
    return false;
  }
  session_start = !sequence_.started() || resync_ || !(from == sender_);
  const std::int64_t step = sequence_.started() ? sequence_.distance(number) : 0;
  if (!session_start && step < 0) {
    // Overtaken in the network: a little behind, and no newer than the newest message taken.
    const bool newer = stamp_step_ms(stamp_ms) > 0;
    if (!newer && static_cast<std::uint64_t>(-step) <= config_.reorder_window) {
      ++counters.out_of_order;
      return false;
    }
    // Back to its first numbers with its clock going on: the controller restarted, however early in
    // its session (the sequence rules alone need the old number well above the new one).
    if (newer && config_.sequence.restart_max > 0 && number <= config_.sequence.restart_max) session_start = true;
  }
  if (session_start) {
    sequence_.reset();
    (void)sequence_.observe(number);
  } else {
    switch (sequence_.observe(number)) {
      case SequenceVerdict::kDuplicate:
        ++counters.duplicate;
        return false;
      case SequenceVerdict::kOutOfOrder:
        ++counters.out_of_order;
        return false;
      case SequenceVerdict::kFarAhead:
        ++counters.far_ahead;
        return false;
      case SequenceVerdict::kRestart:
        session_start = true;
        break;
      case SequenceVerdict::kFirst:
      case SequenceVerdict::kNext:
        break;
    }
  }
  if (session_start && have_sender_) ++counters.restarts;
  // The time stamp's step, wrapping with its field; the cycles elapsed, from the sequence's step.
  const double stamp_step_s = static_cast<double>(stamp_step_ms(stamp_ms)) * 1e-3;
  const double cycles = std::max(1.0, std::round(static_cast<double>(step) / config_.numbers_per_cycle));
  // The controller's clock jumped (set back, or forward by far more than the cycles that passed): the
  // timing starts again from this message rather than reading the jump as a delay.
  const double expected_s = cycles * config_.period_s;
  const bool clock_jump =
      !session_start && (stamp_step_s < 0.0 || std::abs(stamp_step_s - expected_s) > 0.25 + 0.5 * expected_s);
  if (clock_jump) ++counters.clock_jumps;
  timing_.on_message(stamp_step_s, now_s, session_start ? 1 : static_cast<std::uint64_t>(cycles),
                     session_start || clock_jump, counters, arrival);
  last_stamp_ms_ = stamp_ms;
  resync_ = false;
  last_heard_s_ = now_s;
  have_sender_ = true;
  sender_ = from;
  return true;
}

}  // namespace deflex
