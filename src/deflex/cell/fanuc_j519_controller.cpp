// The controller side of FANUC Stream Motion (see fanuc_j519_controller.hpp).
#include "deflex/cell/fanuc_j519_controller.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace deflex::cell {

namespace j519 = fanuc_j519;

FanucJ519Controller::FanucJ519Controller(const FanucJ519ControllerConfig& config, const JointVector& q_start,
                                         DatagramTransport& transport)
    : config_(config),
      transport_(transport),
      check_(config.interval_s, static_cast<std::size_t>(q_start.size()), config.limits),
      target_(q_start),
      position_(q_start),
      encoders_(q_start),
      following_(q_start) {
  buffer_.assign(2048, 0);
}

void FanucJ519Controller::stop_stream(const std::string& alarm) {
  if (!alarm_.empty() || ended_) return;
  alarm_ = alarm;
  queue_.clear();
  moving_ = false;
}

void FanucJ519Controller::raise_alarm(const std::string& code) { stop_stream(code); }

void FanucJ519Controller::restart(double t_s) {
  alarm_.clear();
  ended_ = moving_ = false;
  queue_.clear();
  status_seq_ = 0;
  expected_seq_ = 0;
  ready_at_s_ = t_s + config_.ready_after_s;
  next_status_s_ = t_s;
}

// The table of the limit it enforces (the profile in the header): its strictest value is that limit.
void FanucJ519Controller::answer_threshold(std::size_t size, const DatagramAddress& from) {
  j519::ThresholdRequest rq;
  if (j519::decode(buffer_.data(), size, rq) != j519::DecodeStatus::kOk) {
    ++counters_.ignored;
    return;
  }
  ++counters_.threshold_requests;
  if (!config_.answer_thresholds || streaming_) return;
  const j519::AxisLimits& l = config_.limits[rq.axis - 1];
  const double limit = rq.kind == j519::LimitKind::kVelocity       ? l.velocity
                       : rq.kind == j519::LimitKind::kAcceleration ? l.acceleration
                                                                   : l.jerk;
  j519::ThresholdReply reply;
  reply.axis = rq.axis;
  reply.kind = rq.kind;
  reply.max_cartesian_speed_mm_s = config_.max_cartesian_speed_mm_s;
  reply.interval_ms = static_cast<std::uint32_t>(std::lround(config_.interval_s * 1e3));
  // float32 on the wire, rounded down: the table never allows more than the limit enforced.
  const auto down = [](double v) {
    const auto f = static_cast<float>(v);
    return static_cast<double>(f) > v ? std::nextafter(f, 0.0f) : f;
  };
  for (std::size_t i = 0; i < reply.full_load.size(); ++i) {
    const double full = limit * (1.0 + static_cast<double>(reply.full_load.size() - 1 - i) / 19.0);
    reply.full_load[i] = down(full);
    reply.no_load[i] = down(1.25 * full);
  }
  const std::size_t n = j519::encode(reply, buffer_.data(), buffer_.size());
  if (n > 0 && transport_.send_to(buffer_.data(), n, from)) ++counters_.threshold_replies;
}

// Its version, interval and command buffer; a get of protocol 1's controller goes unanswered.
void FanucJ519Controller::answer_capability(std::size_t size, const DatagramAddress& from) {
  j519::Capability rq;
  if (j519::decode(buffer_.data(), size, rq) != j519::DecodeStatus::kOk || rq.type != j519::kTypeCapabilityGet) {
    ++counters_.ignored;
    return;
  }
  ++counters_.capability_requests;
  if (config_.version < 3 || streaming_) return;
  j519::Capability reply;
  reply.type = j519::kTypeCapabilityGet;
  reply.version = config_.version;
  reply.id = rq.id;
  reply.sampling_rate_ms = static_cast<std::uint32_t>(std::lround(config_.interval_s * 1e3));
  reply.start_move = static_cast<std::uint32_t>(std::min<std::size_t>(config_.start_buffer, 9));
  reply.available_version = config_.version;
  reply.status_uses_tcp = 0;
  const std::size_t n = j519::encode(reply, buffer_.data(), buffer_.size());
  if (n > 0 && transport_.send_to(buffer_.data(), n, from)) ++counters_.capability_replies;
}

void FanucJ519Controller::version_mismatch(std::uint32_t pc_version) {
  stop_stream("MOTN-607 ST: Protocol version mismatch PC " + std::to_string(pc_version) + ", Rob " +
              std::to_string(config_.version));
}

void FanucJ519Controller::read_packets(double t_s) {
  DatagramAddress from;
  for (;;) {
    const long n = transport_.receive(buffer_.data(), buffer_.size(), from);
    if (n < 0) break;
    const auto size = static_cast<std::size_t>(n);
    std::uint32_t type = 0;
    std::uint32_t version = 0;
    if (size > buffer_.size() || !j519::peek_header(buffer_.data(), size, type, version)) {
      ++counters_.ignored;
      continue;
    }
    if (size == j519::kStartStopBytes && (type == j519::kTypeStart || type == j519::kTypeStartV3)) {
      ++counters_.starts;
      if (!streaming_) {
        streaming_ = true;
        pc_ = from;
        restart(t_s);
        if (version != config_.version) version_mismatch(version);
      }
      continue;
    }
    if (size == j519::kStartStopBytes && type == j519::kTypeStop) {
      ++counters_.stops;
      // Its status output ends; with no stream running there is nothing to stop (a PC's client may
      // begin with a stop packet to clear what an earlier session left running).
      if (streaming_) stop_stream("stream stopped by the stop packet");
      streaming_ = false;
      continue;
    }
    if (type == j519::kTypeThreshold) {
      answer_threshold(size, from);
      continue;
    }
    if (type == j519::kTypeCapabilityGet || type == j519::kTypeCapabilitySet) {
      answer_capability(size, from);
      continue;
    }
    j519::Command c;
    std::uint32_t cv = 0;
    if (!streaming_ || !(from == pc_) || j519::decode(buffer_.data(), size, c, cv) != j519::DecodeStatus::kOk) {
      ++counters_.ignored;
      continue;
    }
    if (!alarm_.empty() || ended_) continue;  // the stream has stopped: commands are not taken
    if (cv != config_.version) {
      version_mismatch(cv);
      continue;
    }
    // The first command may answer any status sent; each later one carries the next number.
    const bool in_turn = expected_seq_ == 0 ? (c.sequence >= 1 && c.sequence <= status_seq_)
                                            : (c.sequence == expected_seq_ && c.sequence <= status_seq_);
    if (!in_turn) {
      stop_stream("MOTN-601 ST: Sequence No. error");
      continue;
    }
    expected_seq_ = c.sequence + 1;
    if (queue_.size() >= config_.packet_stack) {
      stop_stream("MOTN-603 ST: command buffer overflow");
      continue;
    }
    queue_.push_back(c);
    ++counters_.commands;
  }
}

void FanucJ519Controller::take_command(double t_s) {
  if (!moving_) {
    if (queue_.size() < config_.start_buffer) return;
    moving_ = true;
    std::array<double, j519::kAxes> deg{};
    for (int i = 0; i < target_.size(); ++i) deg[static_cast<std::size_t>(i)] = rad_to_deg(target_[i]);
    check_.reset(deg);
  }
  if (queue_.empty()) {
    stop_stream("MOTN-603 ST: Receiving interval over");
    return;
  }
  const j519::Command c = queue_.front();
  queue_.pop_front();
  std::size_t axis = 0;
  double value = 0.0;
  const j519::LimitExceeded hit = check_.push(c.target, axis, value);
  if (hit != j519::LimitExceeded::kNone) {
    const char* code = hit == j519::LimitExceeded::kVelocity       ? "MOTN-609"
                       : hit == j519::LimitExceeded::kAcceleration ? "MOTN-610"
                                                                   : "MOTN-611";
    stop_stream(std::string(code) + " ST: joint " + std::to_string(axis + 1) + " " + j519::to_string(hit) +
                " limit exceeded (" + std::to_string(std::abs(value)) + ")");
    return;
  }
  for (int i = 0; i < target_.size(); ++i) target_[i] = deg_to_rad(c.target[static_cast<std::size_t>(i)]);
  ++counters_.taken;
  taken_.push_back(target_);
  delay_.emplace_back(t_s, target_);
  if (c.last) {
    ended_ = true;
    moving_ = false;
  }
}

void FanucJ519Controller::send_status(double t_s, double stamp_s) {
  j519::Status s;
  s.version = config_.version;
  s.sequence = ++status_seq_;
  const bool ready = alarm_.empty() && !ended_ && t_s + 1e-12 >= ready_at_s_;
  s.status_bits = static_cast<std::uint8_t>((ready ? j519::kStatusReady : 0) | j519::kStatusSysReady |
                                            (moving_ ? j519::kStatusInMotion : 0) |
                                            (counters_.commands > 0 ? j519::kStatusCommandReceived : 0));
  if (!alarm_.empty()) s.robot_status = j519::kRobotInError;
  s.time_stamp_ms = static_cast<std::uint32_t>(std::llround(stamp_s * 500.0)) * 2U;  // 2 ms resolution
  const JointVector& q = have_encoders_ ? encoders_ : position_;
  for (int i = 0; i < q.size(); ++i) s.joints_deg[static_cast<std::size_t>(i)] = static_cast<float>(rad_to_deg(q[i]));
  const std::size_t n = j519::encode(config_.version, s, buffer_.data(), buffer_.size());
  if (n > 0 && transport_.send_to(buffer_.data(), n, pc_)) ++counters_.statuses;
}

const JointVector& FanucJ519Controller::tick(double t_s) {
  const double dt = t_s - last_t_s_;
  last_t_s_ = t_s;
  read_packets(t_s);
  if (streaming_ && t_s + 1e-12 >= next_status_s_) {
    // The controller's clock is its interpolation clock: the status is stamped with the interval's own
    // time, however late the simulation got to it.
    const double stamp_s = next_status_s_;
    next_status_s_ += config_.interval_s;
    if (alarm_.empty() && !ended_) take_command(t_s);
    send_status(t_s, stamp_s);
  }
  // The drives follow the newest target taken at least the dead time ago; after an alarm, where the
  // arm is (it decelerates to rest through the servo's lag).
  while (!delay_.empty() && delay_.front().first <= t_s - config_.dead_time_s + 1e-12) {
    following_ = delay_.front().second;
    delay_.pop_front();
  }
  if (!alarm_.empty()) {
    delay_.clear();
    following_ = position_;
  }
  if (dt > 0.0) position_ += (1.0 - std::exp(-dt / config_.servo_lag_s)) * (following_ - position_);
  return position_;
}

void FanucJ519Controller::encoders(const JointVector& q_motor_rad) {
  encoders_ = q_motor_rad;
  have_encoders_ = true;
}

}  // namespace deflex::cell
