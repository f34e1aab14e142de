// The EGM sensor-side endpoint (see egm_sensor_endpoint.hpp).
#include "deflex/egm/egm_sensor_endpoint.hpp"

#include <cstdio>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

EgmSensorEndpoint::EgmSensorEndpoint(OnlineCompensator& compensator, const EgmEndpointConfig& config)
    : comp_(compensator),
      config_(config),
      socket_(config.bind_address, config.port),
      codec_(compensator.model().dof()),
      start_(std::chrono::steady_clock::now()) {
  if (config_.max_packet_bytes < 64 || config_.max_packet_bytes > 65507) {
    throw InputError("EGM endpoint: max_packet_bytes must be 64..65507");
  }
  // One byte more than the limit, so an oversized datagram is seen as such even if MSG_TRUNC lied.
  rx_.assign(config_.max_packet_bytes + 1, 0);
  tx_.assign(1024, 0);
  const int n = compensator.model().dof();
  for (JointVector* q : {&msg_.feedback_joints_deg, &msg_.planned_joints_deg, &newest_.feedback_joints_deg,
                         &newest_.planned_joints_deg, &reply_.planned_joints_deg, &input_.q_planned, &input_.q_feedback}) {
    *q = JointVector::Zero(n);
  }
  EgmCycleRecord blank;
  blank.q_planned = blank.q_feedback = blank.q_command = blank.dtheta = JointVector::Zero(n);
  history_.assign(std::max<std::size_t>(config_.history_cycles, 1), blank);
  last_ = blank;
}

double EgmSensorEndpoint::now_s() const noexcept {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool EgmSensorEndpoint::accept_sequence(std::uint32_t seqno, double now) noexcept {
  if (have_seq_) {
    const auto diff = static_cast<std::int32_t>(seqno - last_seq_);
    const bool silent = now - last_accept_s_ > config_.restart_silence_s;
    const bool restart_jump = diff < 0 && seqno <= config_.restart_seqno_max && last_seq_ > seqno + config_.restart_seqno_max;
    if (diff <= 0 && (silent || restart_jump)) {
      // The controller started again: accept its numbering. The compensator is not reset: that
      // would drop the correction to zero at once, past the rate bound, and a single stray packet
      // with a small sequence number (another sender on the port) would make the real controller's
      // next command jump by the whole correction. The correction follows its new target at the
      // rate bound instead.
      ++counters_.restarts;
    } else if (diff == 0) {
      ++counters_.duplicate;
      return false;
    } else if (diff < 0) {
      ++counters_.out_of_order;
      return false;
    }
  }
  have_seq_ = true;
  last_seq_ = seqno;
  last_accept_s_ = now;
  return true;
}

bool EgmSensorEndpoint::joints_plausible(const EgmRobotMessage& m) const noexcept {
  constexpr double kToleranceRad = kPi / 180.0;
  const RobotModel& model = comp_.model();
  for (int i = 0; i < model.dof(); ++i) {
    const double lo = model.lower_limits()[i] - kToleranceRad;
    const double hi = model.upper_limits()[i] + kToleranceRad;
    const double planned = deg_to_rad(m.planned_joints_deg[i]);
    const double feedback = deg_to_rad(m.feedback_joints_deg[i]);
    if (!(planned >= lo && planned <= hi && feedback >= lo && feedback <= hi)) {
      return false;
    }
  }
  return true;
}

EgmPollResult EgmSensorEndpoint::poll(double timeout_s) noexcept {
  if (!socket_.wait_readable(timeout_s)) {
    return EgmPollResult::kTimeout;
  }
  const auto t_read = std::chrono::steady_clock::now();
  bool have = false;
  // Drain: keep only the newest acceptable packet; older ones of the same drain are superseded.
  for (int i = 0; i < 1024; ++i) {
    const long n = socket_.receive(rx_.data(), rx_.size(), from_);
    if (n < 0) {
      break;
    }
    ++counters_.datagrams;
    if (static_cast<std::size_t>(n) > config_.max_packet_bytes) {
      ++counters_.oversized;
      continue;
    }
    const EgmDecodeStatus st = codec_.decode_robot(rx_.data(), static_cast<std::size_t>(n), msg_);
    switch (st) {
      case EgmDecodeStatus::kOk: break;
      case EgmDecodeStatus::kMalformed: ++counters_.malformed; continue;
      case EgmDecodeStatus::kTruncated: ++counters_.truncated; continue;
      case EgmDecodeStatus::kMissingHeader: ++counters_.missing_header; continue;
      case EgmDecodeStatus::kMissingJoints: ++counters_.missing_joints; continue;
      case EgmDecodeStatus::kNonFinite: ++counters_.non_finite; continue;
      case EgmDecodeStatus::kEmpty: ++counters_.empty; continue;
    }
    // A packet that decodes but whose joints no robot of this model can have (a corrupted or foreign
    // sender) must not be answered: its correction would be computed at a configuration that is not
    // the arm's. The tolerance allows for the controller's own rounding beyond its soft limits.
    if (!joints_plausible(msg_)) {
      ++counters_.out_of_limits;
      continue;
    }
    if (!accept_sequence(msg_.seqno, now_s())) {
      continue;
    }
    if (have) {
      ++counters_.superseded;
    }
    newest_ = msg_;
    newest_from_ = from_;
    have = true;
  }
  if (!have) {
    return EgmPollResult::kRejected;
  }

  input_.t_s = now_s();
  for (int i = 0; i < newest_.planned_joints_deg.size(); ++i) {
    input_.q_planned[i] = deg_to_rad(newest_.planned_joints_deg[i]);
    input_.q_feedback[i] = deg_to_rad(newest_.feedback_joints_deg[i]);
  }
  const CycleOutput out = source_ != nullptr ? comp_.step(input_, *source_) : comp_.step(input_);

  EgmCycleRecord& r = last_;
  r.t_s = input_.t_s;
  r.seqno = newest_.seqno;
  r.tm_ms = newest_.tm_ms;
  r.q_planned = input_.q_planned;
  r.q_feedback = input_.q_feedback;
  r.q_command = out.q_command;
  r.dtheta = out.dtheta;
  r.wrench_base = out.wrench_base;
  r.status = out.status;
  r.replied = false;
  if (out.status == CycleStatus::kForceFault || out.status == CycleStatus::kInvalidInput) {
    fault_pending_ = true;
  }
  EgmPollResult result = EgmPollResult::kNotAnswered;
  if (static_cast<int>(out.status) >= 0 && out.q_command.allFinite()) {
    reply_.seqno = ++reply_seq_;
    reply_.tm_ms = egm_time_stamp_ms(input_.t_s);
    for (int i = 0; i < out.q_command.size(); ++i) {
      reply_.planned_joints_deg[i] = rad_to_deg(out.q_command[i]);
    }
    const std::size_t n = codec_.encode_sensor(reply_, tx_.data(), tx_.size());
    if (n > 0 && socket_.send_to(tx_.data(), n, newest_from_)) {
      ++counters_.replies;
      r.replied = true;
      result = EgmPollResult::kReplied;
    } else {
      ++counters_.send_errors;
    }
  } else {
    ++counters_.invalid_cycles;
  }
  r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count();
  record(r);
  return result;
}

void EgmSensorEndpoint::record(const EgmCycleRecord& r) noexcept {
  history_[history_head_] = r;
  history_head_ = (history_head_ + 1) % history_.size();
  history_count_ = std::min(history_count_ + 1, history_.size());
}

std::uint64_t EgmSensorEndpoint::run(const std::atomic<bool>& stop, const CycleCallback& callback,
                                     double poll_timeout_s, const std::string& fault_dump_csv) {
  std::uint64_t cycles = 0;
  while (!stop.load(std::memory_order_relaxed)) {
    const EgmPollResult r = poll(poll_timeout_s);
    if (r == EgmPollResult::kTimeout || r == EgmPollResult::kRejected) {
      continue;
    }
    ++cycles;
    if (fault_pending_ && !fault_dump_csv.empty()) {
      write_history_csv(fault_dump_csv);  // the cycles that led to the fault, for the post-mortem
      fault_pending_ = false;
    }
    if (callback && !callback(last_)) {
      break;
    }
  }
  return cycles;
}

void EgmSensorEndpoint::write_history_csv(const std::string& path) const {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    throw Error(fmt::format("{}: cannot write the EGM cycle history", path));
  }
  const int n = comp_.model().dof();
  std::string header = "t_s,seqno,tm_ms,status,replied";
  for (const char* name : {"q_planned", "q_feedback", "q_command", "dtheta"}) {
    for (int j = 1; j <= n; ++j) {
      header += fmt::format(",{}{}_rad", name, j);
    }
  }
  header += ",fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,compute_s\n";
  std::fputs(header.c_str(), f);
  const std::size_t size = history_.size();
  const std::size_t first = (history_head_ + size - history_count_) % size;
  for (std::size_t k = 0; k < history_count_; ++k) {
    const EgmCycleRecord& r = history_[(first + k) % size];
    std::string line = fmt::format("{:.6f},{},{},{},{}", r.t_s, r.seqno, r.tm_ms, static_cast<int>(r.status),
                                   r.replied ? 1 : 0);
    for (const JointVector* q : {&r.q_planned, &r.q_feedback, &r.q_command, &r.dtheta}) {
      for (int j = 0; j < q->size(); ++j) {
        line += fmt::format(",{:.12g}", (*q)[j]);
      }
    }
    for (int j = 0; j < 6; ++j) {
      line += fmt::format(",{:.9g}", r.wrench_base[j]);
    }
    line += fmt::format(",{:.9f}\n", r.compute_s);
    std::fputs(line.c_str(), f);
  }
  std::fclose(f);
}

}  // namespace deflex
