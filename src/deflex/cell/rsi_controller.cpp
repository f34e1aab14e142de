// The controller side of KUKA RSI axis correction (see rsi_controller.hpp).
#include "deflex/cell/rsi_controller.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::cell {

const char* to_string(RsiStop s) {
  switch (s) {
    case RsiStop::kRunning:
      return "running";
    case RsiStop::kTimeout:
      return "stopped: Timeout reached (late answers)";
    case RsiStop::kMaxCorrection:
      return "stopped: AXISCORRMON MaxAi exceeded";
  }
  return "unknown";
}

RsiController::RsiController(const RsiControllerConfig& config, const RobotModel& kinematics,
                             std::shared_ptr<const JointTrajectory> program, DatagramTransport& transport,
                             const DatagramAddress& sensor)
    : config_(config),
      model_(kinematics),
      ws_(model_),
      program_(std::move(program)),
      transport_(transport),
      sensor_(sensor) {
  const bool ok = std::isfinite(config_.cycle_s) && config_.cycle_s > 0.0 && config_.timeout >= 1 &&
                  config_.lower_limit_deg <= 0.0 && config_.upper_limit_deg >= 0.0 &&
                  config_.max_correction_deg > 0.0 && config_.correction_dead_time_s >= 0.0 && config_.precision >= 0 &&
                  config_.precision <= 12 && valid_rsi_sentype(config_.sentype) &&
                  (config_.ipoc_bits == 32 || config_.ipoc_bits == 64);
  if (!ok) throw InputError(fmt::format("RSI controller: bad configuration (SENTYPE '{}')", config_.sentype));
  if (program_->dof() != model_.dof()) throw InputError("RSI controller: the program is for another robot");
  const int n = model_.dof();
  buffer_.assign(4096, 0);
  pending_.resize(64);
  for (Pending& p : pending_) p.offset_rad = JointVector::Zero(n);
  applied_ = JointVector::Zero(n);
  planned_ = position_ = encoders_ = program_->points().front();
  robot_.actual_deg = robot_.setpoint_deg = JointVector::Zero(n);
  robot_.has_setpoint = robot_.has_rist = robot_.has_rsol = true;
  answer_.correction_deg = JointVector::Zero(n);
  next_ipoc_ = config_.first_ipoc;
}

void RsiController::restart(std::uint64_t ipoc_jump_ms) {
  counters_.stopped = RsiStop::kRunning;
  counters_.late = 0;
  applied_.setZero();
  pending_count_ = 0;
  awaiting_ = false;
  next_ipoc_ += ipoc_jump_ms;
  if (config_.ipoc_bits == 32) next_ipoc_ &= 0xFFFFFFFFULL;
}

void RsiController::pause(double from_s, double to_s) {
  pause_from_s_ = from_s;
  pause_to_s_ = to_s;
}

void RsiController::pose_of(const JointVector& q, std::array<double, 6>& xyzabc) {
  forward_kinematics(model_, ws_, q);
  const Vector3 p = ws_.base_T_tcp.translation() * 1e3;
  const Matrix3 R = ws_.base_T_tcp.linear();
  // KUKA's A, B, C: rotations about Z, then the new Y, then the new X (R = Rz(A) Ry(B) Rx(C)).
  xyzabc = {p.x(),
            p.y(),
            p.z(),
            rad_to_deg(std::atan2(R(1, 0), R(0, 0))),
            rad_to_deg(std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)))),
            rad_to_deg(std::atan2(R(2, 1), R(2, 2)))};
}

const JointVector& RsiController::tick(double t_s) {
  const double dt = started_ ? t_s - last_t_s_ : 0.0;
  last_t_s_ = t_s;
  started_ = true;
  const int n = model_.dof();
  // The answers that have arrived: the one carrying the awaited IPOC is taken, once.
  DatagramAddress from;
  for (;;) {
    const long got = transport_.receive(buffer_.data(), buffer_.size(), from);
    if (got < 0) break;
    if (!running() || static_cast<std::size_t>(got) > buffer_.size() || !(from == sensor_) ||
        decode_rsi_sensor(buffer_.data(), static_cast<std::size_t>(got), config_.sentype, n, answer_) !=
            RsiDecodeStatus::kOk) {
      ++counters_.ignored;
      continue;
    }
    if (!awaiting_ || answered_ || answer_.ipoc != robot_.ipoc) {
      ++counters_.stale;
      continue;
    }
    answered_ = true;
    ++counters_.answers;
    if (pending_count_ == pending_.size()) {  // full: the oldest is dropped
      pending_head_ = (pending_head_ + 1) % pending_.size();
      --pending_count_;
    }
    Pending& p = pending_[(pending_head_ + pending_count_) % pending_.size()];
    p.due_s = t_s + config_.correction_dead_time_s;
    bool clamped = false;
    for (int i = 0; i < n; ++i) {
      const double v = answer_.correction_deg[i];
      const double c = std::clamp(v, config_.lower_limit_deg, config_.upper_limit_deg);
      clamped = clamped || c != v;
      p.offset_rad[i] = deg_to_rad(c);
    }
    if (clamped) ++counters_.clamped;
    ++pending_count_;
  }

  if (running()) {
    // Absolute offsets: the newest one due replaces the one before; nothing accumulates.
    while (pending_count_ > 0 && pending_[pending_head_].due_s <= t_s + 1e-12) {
      applied_ = pending_[pending_head_].offset_rad;
      pending_head_ = (pending_head_ + 1) % pending_.size();
      --pending_count_;
    }
    if (rad_to_deg(applied_.cwiseAbs().maxCoeff()) > config_.max_correction_deg) stop(RsiStop::kMaxCorrection);
  }
  if (running()) {
    program_t_s_ += dt;
    program_->sample(program_t_s_, planned_);
    position_ = planned_ + applied_;
  }

  if (t_s + 1e-12 >= next_cycle_s_) {
    next_cycle_s_ += config_.cycle_s;
    const bool paused = t_s >= pause_from_s_ && t_s < pause_to_s_;
    if (paused) {
      awaiting_ = false;
      return position_;
    }
    if (running() && awaiting_ && !answered_) {
      ++counters_.late;
      if (counters_.late >= static_cast<std::uint64_t>(config_.timeout)) stop(RsiStop::kTimeout);
    }
    if (running()) {
      send_robot_message();
    } else {
      awaiting_ = false;
    }
  }
  return position_;
}

// This cycle's <Rob>: AIPos and RIst from the encoders, ASPos and RSol from the program, the late
// count and the next IPOC.
void RsiController::send_robot_message() {
  const int n = static_cast<int>(planned_.size());
  robot_.ipoc = next_ipoc_;
  next_ipoc_ += static_cast<std::uint64_t>(std::llround(config_.cycle_s * 1e3));
  if (config_.ipoc_bits == 32) next_ipoc_ &= 0xFFFFFFFFULL;
  robot_.delay = counters_.late;
  const JointVector& actual = have_encoders_ ? encoders_ : position_;
  for (int i = 0; i < n; ++i) {
    robot_.actual_deg[i] = rad_to_deg(actual[i]);
    robot_.setpoint_deg[i] = rad_to_deg(planned_[i]);
  }
  pose_of(actual, robot_.rist);
  pose_of(planned_, robot_.rsol);
  const std::size_t size = encode_rsi_robot(robot_, config_.precision, buffer_.data(), buffer_.size());
  if (size > 0 && transport_.send_to(buffer_.data(), size, sensor_)) ++counters_.sent;
  awaiting_ = true;
  answered_ = false;
}

void RsiController::encoders(const JointVector& q_motor_rad) {
  encoders_ = q_motor_rad;
  have_encoders_ = true;
}

}  // namespace deflex::cell
