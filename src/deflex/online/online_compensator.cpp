// The online compensation cycle (see online_compensator.hpp).
#include "deflex/online/online_compensator.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

void OnlineConfig::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || !(v > 0.0)) {
      throw InputError(fmt::format("online configuration: {} must be finite and > 0 (got {})", name, v));
    }
  };
  positive(period_s, "period_s");
  positive(max_joint_correction_rad, "max_joint_correction_rad");
  positive(max_tcp_correction_m, "max_tcp_correction_m");
  positive(max_correction_rate_rad_s, "max_correction_rate_rad_s");
  positive(max_tcp_rate_m_s, "max_tcp_rate_m_s");
  positive(watchdog_s, "watchdog_s");
  if (!std::isfinite(fault_hold_s) || fault_hold_s < 0.0) {
    throw InputError("online configuration: fault_hold_s must be finite and >= 0");
  }
}

const char* to_string(CycleStatus s) {
  switch (s) {
    case CycleStatus::kOk:
      return "ok";
    case CycleStatus::kNoForceYet:
      return "no_force_yet";
    case CycleStatus::kStaleForce:
      return "stale_force";
    case CycleStatus::kForceFault:
      return "force_fault";
    case CycleStatus::kHeld:
      return "held";
    case CycleStatus::kInvalidInput:
      return "invalid_input";
    case CycleStatus::kOutsideLimits:
      return "outside_limits";
  }
  return "unknown";
}

namespace {
Pose sensor_T_wap_of(const RobotModel& model, const SensorConfig& sensor) {
  return sensor.flange_T_sensor.inverse() * model.flange_T_wap();
}
}  // namespace

OnlineCompensator::OnlineCompensator(const RobotModel& model, const SensorConfig& sensor, const OnlineConfig& config)
    : model_(model),
      config_(config),
      flange_T_sensor_(sensor.flange_T_sensor),
      pipeline_(sensor, sensor_T_wap_of(model, sensor)),
      frames_(model_),
      jac_(6, model.dof()) {
  config_.validate();
  (void)model_.stiffness();  // throws ModelError when the robot file gives no stiffness
  correction_ = JointVector::Zero(model_.dof());
  filter_delay_s_ = dc_group_delay_s(pipeline_.lowpass.design());
  const double per_cycle = std::ceil(std::max(0.0, sensor.sample_rate_hz) * config_.period_s);
  queue_capacity_ = std::max(64, 2 * static_cast<int>(std::min(per_cycle, 1e6)) + 8);
  queue_.resize(static_cast<std::size_t>(queue_capacity_));
}

void OnlineCompensator::push_force(const ForceSample& sample) noexcept {
  if (queue_count_ == queue_capacity_) {
    queue_head_ = (queue_head_ + 1) % queue_capacity_;  // drop the oldest
    --queue_count_;
    ++counters_.samples_dropped;
  }
  queue_[static_cast<std::size_t>((queue_head_ + queue_count_) % queue_capacity_)] = sample;
  ++queue_count_;
}

void OnlineCompensator::drain(ForceSource& source) noexcept {
  ForceSample s;
  // Bounded so that a source flooding faster than we read cannot stall the cycle.
  for (int i = 0; i < 4 * queue_capacity_ && source.latest(s); ++i) {
    push_force(s);
  }
}

CycleOutput OnlineCompensator::step(const CycleInput& input, ForceSource& source) noexcept {
  drain(source);
  return step(input);
}

void OnlineCompensator::reset() noexcept {
  queue_head_ = 0;
  queue_count_ = 0;
  correction_.setZero();
  have_force_ = false;
  wrench_base_.setZero();
  last_fault_t_s_ = -1e300;
  have_cycle_ = false;
  slope_head_ = slope_count_ = 0;
  slope_.setZero();
  pipeline_.reset();
}

void OnlineCompensator::update_slope(double t_s) noexcept {
  // Least-squares slope of the conditioned wrench over the cycles of the last kSlopeWindowS (at
  // least two). Fitted at the cycle rate: the samples inside a cycle are already low-passed.
  slope_t_[static_cast<std::size_t>(slope_head_)] = t_s;
  slope_w_[static_cast<std::size_t>(slope_head_)] = wrench_base_;
  slope_head_ = (slope_head_ + 1) % kSlopeRing;
  slope_count_ = std::min(slope_count_ + 1, kSlopeRing);
  int used = 0;
  double st = 0.0;
  Wrench sw = Wrench::Zero();
  for (int k = 0; k < slope_count_; ++k) {
    const auto i = static_cast<std::size_t>((slope_head_ - 1 - k + kSlopeRing) % kSlopeRing);
    if (k >= 2 && t_s - slope_t_[i] > kSlopeWindowS) break;
    st += slope_t_[i];
    sw += slope_w_[i];
    ++used;
  }
  slope_.setZero();
  if (used < 2) return;
  const double tm = st / used;
  const Wrench wm = sw / used;
  double stt = 0.0;
  Wrench stw = Wrench::Zero();
  for (int k = 0; k < used; ++k) {
    const auto i = static_cast<std::size_t>((slope_head_ - 1 - k + kSlopeRing) % kSlopeRing);
    stt += (slope_t_[i] - tm) * (slope_t_[i] - tm);
    stw += (slope_t_[i] - tm) * (slope_w_[i] - wm);
  }
  if (stt > 0.0) slope_ = stw / stt;
}

// The cycle's stages, in order: the inputs refused or taken; the queued samples conditioned with the
// arm's orientation now; the target correction the model gives for the wrench (or zero); the change
// towards it held to the rate bounds; the command.
CycleOutput OnlineCompensator::step(const CycleInput& in) noexcept {
  CycleOutput out;
  ++counters_.cycles;
  if (refuse(in, out)) return out;
  // Time since the last cycle, at most one period: the rate bound holds per cycle, so after a gap
  // (a silence, a stalled PC, a late cycle) the correction moves by no more than one cycle's worth:
  // the controller takes one command a cycle, whatever the time between them.
  double dt = config_.period_s;
  if (have_cycle_) dt = std::min(in.t_s - last_cycle_t_s_, config_.period_s);
  last_cycle_t_s_ = in.t_s;
  have_cycle_ = true;

  // Sensor orientation from the configuration the arm has now.
  const Workspace* ws = &frames_.at(in.q_feedback);
  condition_queued(ws->base_T_flange.linear() * flange_T_sensor_.linear(), in.t_s, out);
  if (have_force_) update_slope(in.t_s);
  out.wrench_measured_base = wrench_base_;
  Wrench used = wrench_base_ + in.wrench_offset_base;
  if (in.wrench_lead_s > 0.0 && std::isfinite(in.wrench_lead_s)) used += in.wrench_lead_s * slope_;

  const JointVector target = target_correction(in, used, ws, out);
  out.wrench_base = out.status == CycleStatus::kOk && used.allFinite() ? used : wrench_base_;
  if (out.status != CycleStatus::kOk) {
    point_jacobian(*ws, ws->base_T_tcp.translation(), jac_);  // at the feedback here
  }
  // jac_ is now the TCP Jacobian at the configuration `ws` holds.
  approach(target, dt, out);
  out.dtheta = correction_;
  out.q_command = in.q_planned - correction_;
  out.tcp_deflection_base_m = jac_.topRows<3>() * correction_;
  out.tcp_correction_m = out.tcp_deflection_base_m.norm();
  if (!model_.within_limits(out.q_command, kCycleLimitToleranceRad)) {
    // The correction takes a joint of a program at its limit beyond it.
    ++counters_.invalid_inputs;
    out.status = CycleStatus::kOutsideLimits;
    out.q_command.setZero();
  }
  return out;
}

bool OnlineCompensator::refuse(const CycleInput& in, CycleOutput& out) noexcept {
  const int n = model_.dof();
  const bool invalid = in.q_planned.size() != n || in.q_feedback.size() != n || !in.q_planned.allFinite() ||
                       !in.q_feedback.allFinite() || !std::isfinite(in.t_s) ||
                       (have_cycle_ && in.t_s < last_cycle_t_s_) || !in.wrench_offset_base.allFinite() ||
                       std::isnan(in.wrench_lead_s);
  // Joints beyond the limits: a command for them is one no controller should be given (a program
  // or feedback in the wrong unit, a wrong robot file); the status says so and nothing is commanded.
  const bool outside = !invalid && (!model_.within_limits(in.q_planned, kCycleLimitToleranceRad) ||
                                    !model_.within_limits(in.q_feedback, kCycleLimitToleranceRad));
  if (!invalid && !outside) return false;
  ++counters_.invalid_inputs;
  out.status = invalid ? CycleStatus::kInvalidInput : CycleStatus::kOutsideLimits;
  out.q_command = JointVector::Zero(n);
  out.dtheta = JointVector::Zero(n);
  return true;
}

void OnlineCompensator::condition_queued(const Matrix3& base_R_sensor, double t_s, CycleOutput& out) noexcept {
  // Every queued sample with this cycle's orientation.
  while (queue_count_ > 0) {
    const ForceSample& s = queue_[static_cast<std::size_t>(queue_head_)];
    queue_head_ = (queue_head_ + 1) % queue_capacity_;
    --queue_count_;
    const ConditionedWrench c = pipeline_.step(s, base_R_sensor);
    ++out.samples_used;
    if (c.status == PipelineStatus::kFault) {
      ++counters_.samples_fault;
      last_fault_t_s_ = t_s;
    } else if (c.status == PipelineStatus::kInvalidSample) {
      ++counters_.samples_invalid;
    } else {
      ++counters_.samples_ok;
      wrench_base_ = c.wrench_base;
      have_force_ = true;
      last_force_t_s_ = t_s;
    }
  }
}

JointVector OnlineCompensator::target_correction(const CycleInput& in, const Wrench& used, const Workspace*& ws,
                                                 CycleOutput& out) noexcept {
  // The model's deflection, or zero when the force cannot be trusted.
  const int n = model_.dof();
  JointVector target = JointVector::Zero(n);
  out.force_age_s = have_force_ ? in.t_s - last_force_t_s_ : 0.0;
  if (!have_force_) {
    out.status = CycleStatus::kNoForceYet;
  } else if (in.t_s - last_fault_t_s_ <= config_.fault_hold_s) {
    out.status = CycleStatus::kForceFault;
  } else if (out.force_age_s > config_.watchdog_s) {
    out.status = CycleStatus::kStaleForce;
  } else if (in.hold_to_zero) {
    out.status = CycleStatus::kHeld;
  } else {
    out.status = CycleStatus::kOk;
  }
  if (out.status != CycleStatus::kOk) return target;
  // dtheta = K^-1 J_wap(q)^T W, at the feedback or at the configuration the command is for (the
  // frames there computed once a cycle, whoever asked first).
  if (config_.jacobian_at == JacobianAt::kPlanned) ws = &frames_.at(in.q_planned);
  point_jacobian(*ws, ws->base_T_wap.translation(), jac_);
  target = model_.compliance().cwiseProduct(jac_.transpose() * used);
  if (!target.allFinite()) target.setZero();
  // Size bounds: per joint, then the TCP translation it produces (scaled as a whole, so the
  // direction of the correction is kept).
  for (int i = 0; i < n; ++i) {
    const double clamped = std::clamp(target[i], -config_.max_joint_correction_rad, config_.max_joint_correction_rad);
    out.size_limited = out.size_limited || clamped != target[i];
    target[i] = clamped;
  }
  if (!model_.wap_is_tcp()) point_jacobian(*ws, ws->base_T_tcp.translation(), jac_);
  const double tcp_m = (jac_.topRows<3>() * target).norm();
  if (tcp_m > config_.max_tcp_correction_m) {
    target *= config_.max_tcp_correction_m / tcp_m;
    out.size_limited = true;
  }
  return target;
}

void OnlineCompensator::approach(const JointVector& target, double dt, CycleOutput& out) noexcept {
  // Rate bounds, joint and TCP; also the ramp to zero when the target dropped to zero. The change is
  // scaled as a whole, not clamped joint by joint: the new correction then lies on the segment from
  // the old one to the target, and as both meet the size bounds (a box and a TCP ball, convex sets)
  // so does every cycle of the ramp. Clamping each joint bent the path and could pass the TCP bound.
  const JointVector change = target - correction_;
  double scale = 1.0;
  const double largest = change.cwiseAbs().maxCoeff();
  const double max_step = config_.max_correction_rate_rad_s * dt;
  if (largest > max_step) scale = max_step / largest;
  const double tcp_change = (jac_.topRows<3>() * change).norm();
  const double max_tcp_step = config_.max_tcp_rate_m_s * dt;
  if (tcp_change * scale > max_tcp_step) scale = max_tcp_step / tcp_change;
  if (scale < 1.0) {
    correction_ += scale * change;
    out.rate_limited = true;
  } else {
    correction_ += change;
  }
}

}  // namespace deflex
