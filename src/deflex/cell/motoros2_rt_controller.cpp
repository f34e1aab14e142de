// The controller side of MotoROS2's real-time interface (see motoros2_rt_controller.hpp).
#include "deflex/cell/motoros2_rt_controller.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace deflex::cell {

namespace rt = motoros2_rt;

Motoros2RtController::Motoros2RtController(const Motoros2RtControllerConfig& config, const JointVector& q_start,
                                           DatagramTransport& transport)
    : config_(config),
      transport_(transport),
      command_(q_start),
      shortfall_(JointVector::Zero(q_start.size())),
      position_(q_start),
      encoders_(q_start),
      following_(q_start) {
  buffer_.assign(8192, 0);
  last_reply_.assign(rt::kReplyBytes, 0);
}

void Motoros2RtController::drop(const std::string& why) {
  if (dropped_.empty()) dropped_ = why;
}

void Motoros2RtController::stop(const std::string& why) {
  drop(why);
  estop_ = true;
}

void Motoros2RtController::send_status(double t_s) {
  if (config_.status_port < 0 || !have_pc_ || t_s + 1e-12 < next_status_s_) return;
  next_status_s_ = t_s + config_.status_period_s;
  rt::RobotState s;
  s.drives_powered = !estop_;
  s.e_stopped = estop_;
  s.play_mode = true;
  s.motion_possible = !estop_;
  s.error = estop_;
  s.error_code = estop_ ? 1 : 0;  // the stand-in's own code, not a Yaskawa alarm number
  std::array<unsigned char, rt::kRobotStateBytes> b{};
  const std::size_t n = rt::encode(s, b.data(), b.size());
  const DatagramAddress to{pc_.ipv4, static_cast<std::uint16_t>(config_.status_port)};
  if (n > 0 && transport_.send_to(b.data(), n, to)) ++counters_.statuses;
}

void Motoros2RtController::restart(double t_s) {
  dropped_.clear();
  estop_ = false;
  have_pc_ = have_last_ = false;
  last_reply_size_ = 0;
  last_command_s_ = t_s;
  command_ = position_;
  shortfall_.setZero();
  truncated_last_ = false;
  delay_.clear();
  following_ = position_;
}

// One command taken at this clock: its increment (within the axis' maximum, truncated by the FSU) is
// added to the command position and answered.
void Motoros2RtController::apply(const rt::Command& c, const DatagramAddress& from, double t_s) {
  const auto g = static_cast<std::size_t>(config_.group);
  const double max_inc = config_.max_speed_rad_s * config_.period_s;
  const double fsu_inc = config_.fsu_speed_rad_s * config_.period_s;
  JointVector inc(command_.size());
  for (int j = 0; j < inc.size(); ++j) {
    inc[j] = c.delta[g][static_cast<std::size_t>(j)];
    if (std::abs(inc[j]) > max_inc) {
      drop("joint " + std::to_string(j + 1) + "'s increment is above its maximum increment per interpolation cycle");
      return;
    }
  }
  increments_.push_back(inc);
  bool truncated = false;
  for (int j = 0; j < inc.size(); ++j) {
    const double applied = std::clamp(inc[j], -fsu_inc, fsu_inc);
    truncated = truncated || applied != inc[j];
    shortfall_[j] = inc[j] - applied;
    command_[j] += applied;
  }
  if (truncated) ++counters_.truncated;
  ++counters_.taken;
  taken_.push_back(command_);
  delay_.emplace_back(t_s, command_);
  rt::Reply r;
  r.sequence_echo = c.sequence;
  const JointVector& q = have_encoders_ ? encoders_ : position_;
  for (int j = 0; j < q.size(); ++j) {
    r.feedback_joints[g][static_cast<std::size_t>(j)] = q[j];
    // This reply still shows the whole increment; the truncation shows in the next one, with the flag.
    r.command_joints[g][static_cast<std::size_t>(j)] = command_[j] + shortfall_[j];
  }
  r.fsu_truncated = truncated_last_;
  truncated_last_ = truncated;
  last_reply_size_ = rt::encode(r, last_reply_.data(), last_reply_.size());
  if (last_reply_size_ > 0 && transport_.send_to(last_reply_.data(), last_reply_size_, from)) ++counters_.replies;
}

// One datagram; true when it was a command taken (the rest queued are then discarded).
bool Motoros2RtController::handle(const unsigned char* data, std::size_t size, const DatagramAddress& from,
                                  double t_s) {
  if (have_pc_ && !(from == pc_)) {
    drop("a command from a second sender");
    return false;
  }
  rt::Command c;
  const rt::DecodeStatus d = rt::decode(data, size, c);
  if (d != rt::DecodeStatus::kOk) {
    drop(std::string("a command it cannot take (") + rt::to_string(d) + ")");
    return false;
  }
  if (c.kind != rt::IncrementKind::kJoint) {
    drop("a packet type that is not the activated mode's");
    return false;
  }
  if (!have_pc_) {
    pc_ = from;
    have_pc_ = true;
  }
  last_command_s_ = t_s;
  if (!have_last_) {
    if (c.sequence != 0) {
      drop("the session's first command is not number 0");
      return false;
    }
  } else {
    const std::int32_t ahead = rt::sequence_ahead(last_sequence_, c.sequence);
    if (ahead <= 0) {
      ++counters_.duplicates;
      if (last_reply_size_ > 0 && transport_.send_to(last_reply_.data(), last_reply_size_, from)) ++counters_.replies;
      return false;
    }
    if (ahead > config_.max_sequence_gap) {
      drop("Missed too many command packets");
      return false;
    }
    counters_.skipped += static_cast<std::uint64_t>(ahead - 1);
  }
  have_last_ = true;
  last_sequence_ = c.sequence;
  apply(c, from, t_s);
  return true;
}

void Motoros2RtController::read_commands(double t_s) {
  DatagramAddress from;
  bool taken = false;
  for (;;) {
    const long n = transport_.receive(buffer_.data(), buffer_.size(), from);
    if (n < 0) break;
    if (!dropped_.empty()) continue;
    if (taken) {
      ++counters_.purged;
      continue;
    }
    taken = handle(buffer_.data(), static_cast<std::size_t>(n), from, t_s);
  }
}

const JointVector& Motoros2RtController::tick(double t_s) {
  const double dt = t_s - last_t_s_;
  // The interpolation clock: a command is taken at most once a period.
  const bool clock = std::floor(t_s / config_.period_s + 1e-9) > std::floor(last_t_s_ / config_.period_s + 1e-9);
  last_t_s_ = t_s;
  if (clock) read_commands(t_s);
  send_status(t_s);
  if (dropped_.empty() && config_.timeout_s >= 0.0 && t_s - last_command_s_ > config_.timeout_s) {
    drop("no command for timeout_for_rt_msg");
  }
  while (!delay_.empty() && delay_.front().first <= t_s - config_.dead_time_s + 1e-12) {
    following_ = delay_.front().second;
    delay_.pop_front();
  }
  if (!dropped_.empty()) {
    // The session is over: the drives stop where they are.
    delay_.clear();
    following_ = position_;
  }
  if (dt > 0.0) position_ += (1.0 - std::exp(-dt / config_.servo_lag_s)) * (following_ - position_);
  return position_;
}

void Motoros2RtController::encoders(const JointVector& q_motor_rad) {
  encoders_ = q_motor_rad;
  have_encoders_ = true;
}

}  // namespace deflex::cell
