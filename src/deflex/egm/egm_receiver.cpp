// The receiving half of deflex's EGM links (see egm_receiver.hpp).
#include "deflex/egm/egm_receiver.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

void EgmReceiverConfig::validate() const {
  if (max_packet_bytes < 64 || max_packet_bytes > 65507) {
    throw InputError("EGM link: max_packet_bytes must be 64..65507");
  }
  if (!std::isfinite(restart_silence_s) || !(restart_silence_s > 0.0)) {
    throw InputError("EGM link: restart silence must be > 0 s");
  }
  if (max_seqno_ahead < 1 || confirm_jump < 1 || confirm_jump > 1000) {
    throw InputError("EGM link: max_seqno_ahead must be >= 1 and confirm_jump 1..1000");
  }
  if (!std::isfinite(period_s) || !(period_s > 0.0)) {
    throw InputError("EGM link: the controller's period must be > 0 s");
  }
}

namespace {
// EGM's seqno counts cycles and wraps at 2^32; header.tm is a 32-bit millisecond stamp.
ControllerGateConfig egm_gate(const EgmReceiverConfig& c) {
  ControllerGateConfig g;
  g.sequence.bits = 32;
  g.sequence.max_ahead = c.max_seqno_ahead;
  g.sequence.restart_max = c.restart_seqno_max;
  g.sequence.confirm = c.confirm_jump;
  g.restart_silence_s = c.restart_silence_s;
  g.period_s = c.period_s;
  g.numbers_per_cycle = 1.0;
  g.stamp_bits = 32;
  return g;
}
}  // namespace

EgmReceiver::EgmReceiver(DatagramTransport& transport, const Clock& clock, const RobotModel& model,
                         const EgmReceiverConfig& config, LinkCounters& counters)
    : transport_(transport),
      clock_(clock),
      config_(config),
      counters_(counters),
      codec_(model.dof()),
      gate_(egm_gate(config)) {
  config_.validate();
  // The tolerance allows for the controller's own rounding beyond its soft limits.
  lower_ = model.lower_limits().array() - kPi / 180.0;
  upper_ = model.upper_limits().array() + kPi / 180.0;
  // One byte more than the limit, so an oversized datagram is seen as such even if MSG_TRUNC lied.
  rx_.assign(config_.max_packet_bytes + 1, 0);
  for (EgmRobotMessage* m : {&msg_, &newest_}) {
    m->feedback_joints_deg = m->planned_joints_deg = JointVector::Zero(model.dof());
  }
}

bool EgmReceiver::plausible(const EgmRobotMessage& m) const noexcept {
  for (int i = 0; i < lower_.size(); ++i) {
    const double fb = deg_to_rad(m.feedback_joints_deg[i]);
    if (!(fb >= lower_[i] && fb <= upper_[i])) return false;
    if (m.has_planned) {
      const double pl = deg_to_rad(m.planned_joints_deg[i]);
      if (!(pl >= lower_[i] && pl <= upper_[i])) return false;
    }
  }
  return true;
}

// Decodes the datagram in rx_ into msg_; a refused one is counted by its reason.
bool EgmReceiver::decoded(std::size_t size) noexcept {
  switch (codec_.decode_robot(rx_.data(), size, msg_)) {
    case EgmDecodeStatus::kOk:
      return true;
    case EgmDecodeStatus::kMalformed:
      ++counters_.malformed;
      return false;
    case EgmDecodeStatus::kTruncated:
      ++counters_.truncated;
      return false;
    case EgmDecodeStatus::kMissingHeader:
      ++counters_.missing_header;
      return false;
    case EgmDecodeStatus::kMissingJoints:
      ++counters_.missing_joints;
      return false;
    case EgmDecodeStatus::kNonFinite:
      ++counters_.non_finite;
      return false;
    case EgmDecodeStatus::kEmpty:
      ++counters_.empty;
      return false;
    case EgmDecodeStatus::kSequenceOutOfRange:
      ++counters_.sequence_out_of_range;
      return false;
    case EgmDecodeStatus::kMissingRequired:
      ++counters_.missing_required;
      return false;
  }
  return false;
}

EgmReceiver::Result EgmReceiver::drain(double timeout_s, bool& restarted) noexcept {
  restarted = false;
  if (!transport_.wait_readable(timeout_s)) {
    return Result::kNothing;
  }
  bool have = false;
  const double now = clock_.now_s();
  // Drain: keep only the newest acceptable packet; older ones of the same drain are superseded.
  for (int i = 0; i < 1024; ++i) {
    DatagramAddress from;
    const long n = transport_.receive(rx_.data(), rx_.size(), from);
    if (n < 0) {
      break;
    }
    ++counters_.datagrams;
    gate_.heard(from, now);  // the silence that ends a session counts from any datagram of the controller
    if (static_cast<std::size_t>(n) > config_.max_packet_bytes) {
      ++counters_.oversized;
      continue;
    }
    if (!decoded(static_cast<std::size_t>(n))) continue;
    // A packet whose joints no robot of this model can have (a corrupted or foreign sender) must not
    // be answered: its correction would be computed at a configuration that is not the arm's.
    if (!plausible(msg_)) {
      ++counters_.out_of_limits;
      continue;
    }
    bool session_start = false;
    if (!gate_.take(from, msg_.seqno, msg_.tm_ms, now, counters_, session_start, msg_arrival_)) {
      continue;
    }
    restarted = restarted || session_start;
    if (have) {
      ++counters_.superseded;
    }
    last_accept_s_ = now;
    receipt_age_s_ = transport_.since_receipt_s();
    taken_at_s_ = clock_.now_s();
    newest_ = msg_;
    arrival_ = msg_arrival_;
    have = true;
  }
  return have ? Result::kMessage : Result::kNoneUsable;
}

bool EgmReceiver::reply(const unsigned char* data, std::size_t size) noexcept {
  if (!gate_.has_controller() || !transport_.send_to(data, size, gate_.controller())) {
    ++counters_.send_errors;
    return false;
  }
  ++counters_.replies;
  return true;
}

}  // namespace deflex
