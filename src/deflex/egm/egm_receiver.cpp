// The receiving half of deflex's EGM links (see egm_receiver.hpp).
#include "deflex/egm/egm_receiver.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

void EgmReceiverConfig::validate() const {
  if (max_packet_bytes < 64 || max_packet_bytes > 65507) {
    throw InputError("EGM link: max_packet_bytes must be 64..65507");
  }
  if (!std::isfinite(restart_silence_s) || !(restart_silence_s > 0.0)) {
    throw InputError("EGM link: restart silence must be > 0 s");
  }
}

EgmReceiver::EgmReceiver(DatagramTransport& transport, const Clock& clock, const RobotModel& model,
                         const EgmReceiverConfig& config, LinkCounters& counters)
    : transport_(transport), clock_(clock), config_(config), counters_(counters), codec_(model.dof()) {
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
    if (static_cast<std::size_t>(n) > config_.max_packet_bytes) {
      ++counters_.oversized;
      continue;
    }
    switch (codec_.decode_robot(rx_.data(), static_cast<std::size_t>(n), msg_)) {
      case EgmDecodeStatus::kOk: break;
      case EgmDecodeStatus::kMalformed: ++counters_.malformed; continue;
      case EgmDecodeStatus::kTruncated: ++counters_.truncated; continue;
      case EgmDecodeStatus::kMissingHeader: ++counters_.missing_header; continue;
      case EgmDecodeStatus::kMissingJoints: ++counters_.missing_joints; continue;
      case EgmDecodeStatus::kNonFinite: ++counters_.non_finite; continue;
      case EgmDecodeStatus::kEmpty: ++counters_.empty; continue;
    }
    // A packet whose joints no robot of this model can have (a corrupted or foreign sender) must not
    // be answered: its correction would be computed at a configuration that is not the arm's.
    if (!plausible(msg_)) {
      ++counters_.out_of_limits;
      continue;
    }
    const bool silent = have_seq_ && now - last_accept_s_ > config_.restart_silence_s;
    // One controller owns the link; another sender may take over only after the controller fell silent.
    if (have_sender_ && !(from == sender_) && !silent) {
      ++counters_.foreign_sender;
      continue;
    }
    bool session_start = !have_seq_ || silent || !(from == sender_);
    if (have_seq_ && !session_start) {
      const auto diff = static_cast<std::int32_t>(msg_.seqno - last_seq_);
      const bool restart_jump =
          diff < 0 && msg_.seqno <= config_.restart_seqno_max && last_seq_ > msg_.seqno + config_.restart_seqno_max;
      if (restart_jump) {
        session_start = true;
      } else if (diff == 0) {
        ++counters_.duplicate;
        continue;
      } else if (diff < 0) {
        ++counters_.out_of_order;
        continue;
      }
    }
    if (session_start && have_seq_) {
      ++counters_.restarts;
    }
    restarted = restarted || session_start;
    if (have) {
      ++counters_.superseded;
    }
    have_seq_ = true;
    last_seq_ = msg_.seqno;
    last_accept_s_ = now;
    have_sender_ = true;
    sender_ = from;
    newest_ = msg_;
    have = true;
  }
  return have ? Result::kMessage : Result::kNoneUsable;
}

bool EgmReceiver::reply(const unsigned char* data, std::size_t size) noexcept {
  if (!have_sender_ || !transport_.send_to(data, size, sender_)) {
    ++counters_.send_errors;
    return false;
  }
  ++counters_.replies;
  return true;
}

}  // namespace deflex
