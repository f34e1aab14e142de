// The one link cycle (see link_cycle.hpp).
#include "deflex/link/link_cycle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>

#include <fmt/format.h>

#include "deflex/link/correction_smoother.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

const char* to_string(CommandForm f) {
  switch (f) {
    case CommandForm::kJointTarget:
      return "joint target";
    case CommandForm::kJointOffset:
      return "joint offset";
    case CommandForm::kTcpOffset:
      return "TCP offset";
  }
  return "unknown";
}

double CommandLimits::resolution_rad(double v) const noexcept {
  switch (rounding) {
    case WireRounding::kExact:
      return 0.0;
    // Half an ulp of a float32 of that size, and a little more for the double sums around it.
    case WireRounding::kFloat32:
      return std::max(std::abs(v), 1.0) * static_cast<double>(std::numeric_limits<float>::epsilon());
    case WireRounding::kDecimalsDeg:
      return deg_to_rad(0.5 * std::pow(10.0, -decimals)) * (1.0 + 1e-9);
    case WireRounding::kFloat32Deg:
      return deg_to_rad(std::max(std::abs(rad_to_deg(v)), 1.0)) *
             static_cast<double>(std::numeric_limits<float>::epsilon());
  }
  return 0.0;
}

double CommandLimits::round(double v) const noexcept {
  switch (rounding) {
    case WireRounding::kExact:
      return v;
    case WireRounding::kFloat32:
      return static_cast<double>(static_cast<float>(v));
    case WireRounding::kDecimalsDeg: {
      const double scale = std::pow(10.0, decimals);
      return deg_to_rad(std::round(rad_to_deg(v) * scale) / scale);
    }
    case WireRounding::kFloat32Deg:
      return deg_to_rad(static_cast<double>(static_cast<float>(rad_to_deg(v))));
  }
  return v;
}

void CommandLimits::validate(int dof) const {
  const auto positive = [](double v, const char* what) {
    if (!std::isfinite(v) || !(v > 0.0))
      throw InputError(fmt::format("command limits: {} must be > 0 (got {})", what, v));
  };
  positive(joint_bound_rad, "the joint bound");
  positive(tcp_bound_m, "the TCP bound");
  if (form == CommandForm::kTcpOffset) {
    positive(tcp_step_m, "the TCP step limit");
  } else {
    if (joint_step_rad.size() != dof) {
      throw InputError(
          fmt::format("command limits: {} joint step limits for a robot of {} joints", joint_step_rad.size(), dof));
    }
    for (int j = 0; j < dof; ++j) positive(joint_step_rad[j], "a joint's step limit");
  }
  if (rounding == WireRounding::kDecimalsDeg && (decimals < 1 || decimals > 12)) {
    throw InputError("command limits: 1..12 decimals");
  }
}

std::string CommandLimits::describe() const {
  if (form == CommandForm::kTcpOffset) {
    return fmt::format("{}: bound {:g} mm, step limit {:.4g} mm a cycle", to_string(form), tcp_bound_m * 1e3,
                       tcp_step_m * 1e3);
  }
  return fmt::format("{}: bound {:g} deg a joint and {:g} mm at the TCP, step limit {:.4g}..{:.4g} deg a cycle",
                     to_string(form), rad_to_deg(joint_bound_rad), tcp_bound_m * 1e3,
                     rad_to_deg(joint_step_rad.minCoeff()), rad_to_deg(joint_step_rad.maxCoeff()));
}

CommandLimits command_limits(CommandForm form, const OnlineConfig& online, int dof, const JointTrajectory* program,
                             const JointStreamConfig* stream) {
  online.validate();
  const double period = online.period_s;
  // The correction alone moves by at most the rate bound a cycle: that step must fit in its bound, or
  // a single cycle could take the command from one side of the bound to beyond the other.
  const double joint_step = online.max_correction_rate_rad_s * period;
  if (joint_step > online.max_joint_correction_rad) {
    throw InputError(fmt::format(
        "the correction's rate bound allows {:.4g} deg a cycle ({:g} deg/s x {:g} ms), more than its bound of {:g} deg "
        "a joint: lower --max-rate-deg-s or --period-ms, or raise --max-joint-correction-deg",
        rad_to_deg(joint_step), rad_to_deg(online.max_correction_rate_rad_s), period * 1e3,
        rad_to_deg(online.max_joint_correction_rad)));
  }
  const double tcp_step = online.max_tcp_rate_m_s * period;
  if (tcp_step > online.max_tcp_correction_m) {
    throw InputError(
        fmt::format("the correction's TCP rate bound allows {:.4g} mm a cycle ({:g} mm/s x {:g} ms), more than its TCP "
                    "bound of {:g} "
                    "mm: lower --max-tcp-rate-mm-s or --period-ms, or raise --max-tcp-correction-mm",
                    tcp_step * 1e3, online.max_tcp_rate_m_s * 1e3, period * 1e3, online.max_tcp_correction_m * 1e3));
  }
  CommandLimits l;
  l.form = form;
  l.joint_bound_rad = online.max_joint_correction_rad;
  l.tcp_bound_m = online.max_tcp_correction_m;
  l.joint_step_rad = JointVector::Constant(dof, joint_step + 1e-12);
  l.tcp_step_m = tcp_step + 1e-12;
  if (form == CommandForm::kJointTarget) {
    if (program == nullptr || stream == nullptr) {
      throw InputError("command limits: a joint target link needs its program and its stream settings");
    }
    if (program->dof() != dof) {
      throw InputError(fmt::format("command limits: the program has {} joints, the robot {}", program->dof(), dof));
    }
    // The nominal moves one period of the program a cycle (at most its peak speed times the period,
    // by the mean value theorem on the interpolation), the ramp-in blend at most 1.5 x its offset over
    // the ramp (the smoothstep's peak slope), and the correction by its rate bound.
    const double blend_speed = stream->ramp_in_s > 0.0 ? 1.5 * stream->start_tolerance_rad / stream->ramp_in_s : 0.0;
    for (int j = 0; j < dof; ++j) {
      l.joint_step_rad[j] = period * (program->peak_speed()[j] * (1.0 + 1e-9) + blend_speed) + joint_step + 1e-12;
    }
  }
  return l;
}

LinkCycle::LinkCycle(OnlineCompensator& compensator, OnlineStrategy& strategy, const CommandLimits& limits,
                     std::size_t history_cycles, LinkCounters& counters)
    : comp_(compensator),
      strategy_(strategy),
      limits_(limits),
      counters_(counters),
      history_(history_cycles, compensator.model().dof()),
      motion_(compensator.model().dof()) {
  const int n = compensator.model().dof();
  limits_.validate(n);
  for (JointVector* q : {&input_.q_planned, &input_.q_feedback, &command_, &previous_command_, &reference_,
                         &last_dtheta_, &last_sent_, &out_.dtheta, &out_.q_command}) {
    *q = JointVector::Zero(n);
  }
  record_ = history_.blank();
}

const JointVector& LinkCycle::lead_target(const JointVector& from, double lead_s) noexcept {
  return motion_.lead(from, lead_s, strategy_.kind() == StrategyKind::kPredictive);
}

void LinkCycle::anchor_joints(const JointVector& q, bool after_silence) noexcept {
  previous_command_ = q;
  have_previous_ = true;
  hold_last_sent_ = !after_silence && has_sent();
}

void LinkCycle::anchor_tcp(const Vector3& offset_m, bool after_silence) noexcept {
  previous_offset_m_ = offset_m;
  have_previous_ = true;
  hold_last_sent_ = !after_silence && has_sent();
}

void LinkCycle::restart_from_zero(bool after_silence) noexcept {
  comp_.reset();
  last_dtheta_.setZero();
  if (smoother_ != nullptr) smoother_->reset(last_dtheta_);
  previous_command_.setZero();
  previous_offset_m_.setZero();
  have_previous_ = true;
  hold_last_sent_ = !after_silence && has_sent();
}

double LinkCycle::reanchor_gap(const JointVector& q) const noexcept {
  if (!has_sent() || limits_.form == CommandForm::kTcpOffset) return 0.0;
  return ((q - last_sent_).cwiseAbs().array() / limits_.joint_step_rad.array()).maxCoeff();
}

double LinkCycle::reanchor_gap(const Vector3& offset_m) const noexcept {
  if (!has_sent() || limits_.form != CommandForm::kTcpOffset) return 0.0;
  return (offset_m - last_sent_offset_m_).norm() / limits_.tcp_step_m;
}

// After a re-anchor without a silence the controller may hold either the anchor or the last command
// sent: the command is moved to the nearest point within the step limit of both (per joint an
// interval; for the TCP offset the meet of two balls, by alternating projections). Where the two are
// more than two limits apart there is no such point; the guard then refuses the command.
void LinkCycle::hold_near_last_sent() noexcept {
  if (!hold_last_sent_) return;
  if (limits_.form == CommandForm::kTcpOffset) {
    const double r = limits_.tcp_step_m;
    for (int k = 0; k < 32; ++k) {
      for (const Vector3* centre : {&previous_offset_m_, &last_sent_offset_m_}) {
        const Vector3 d = offset_m_ - *centre;
        if (d.norm() > r) {
          offset_m_ = *centre + d * (r / d.norm());
          record_.step_limited = true;
        }
      }
    }
    return;
  }
  for (int j = 0; j < command_.size(); ++j) {
    const double s = limits_.joint_step_rad[j];
    const double lo = std::max(previous_command_[j], last_sent_[j]) - s;
    const double hi = std::min(previous_command_[j], last_sent_[j]) + s;
    if (lo <= hi && (command_[j] < lo || command_[j] > hi)) {
      command_[j] = std::clamp(command_[j], lo, hi);
      record_.step_limited = true;
    }
  }
}

LinkCycle::Verdict LinkCycle::run(const CycleRequest& rq) noexcept {
  ++stats_.cycles;
  LinkCycleRecord& r = record_;
  r.t_s = rq.t_s;
  r.program_time_s = rq.program_time_s;
  r.sequence = rq.sequence;
  r.q_nominal = *rq.nominal;
  if (rq.blend != nullptr) {
    r.q_blend = *rq.blend;
  } else {
    r.q_blend.setZero();
  }
  r.q_feedback = *rq.feedback;
  r.delay_s = rq.delay_s;
  r.arrival = rq.arrival;
  r.session_start = rq.session_start;
  r.replied = r.step_limited = false;
  r.deviation_rad = r.deviation_m = r.step_rad = r.step_m = r.step_fraction = 0.0;
  r.rotation_uncorrected_rad = 0.0;

  // 1-2: the strategy, then the compensator.
  input_.t_s = rq.t_s;
  input_.q_planned = *rq.target;
  input_.q_feedback = *rq.feedback;
  const StrategyStatus ss =
      strategy_.prepare(input_, *rq.feedback, *rq.target, rq.lead_s, comp_.filter_delay_s(), comp_.frames());
  input_.hold_to_zero = input_.hold_to_zero || rq.hold || ss != StrategyStatus::kOk;
  out_ = force_ != nullptr ? comp_.step(input_, *force_) : comp_.step(input_);
  if (smoother_ != nullptr && static_cast<int>(out_.status) >= 0) out_.dtheta = smoother_->step(out_.dtheta);
  r.dtheta = out_.dtheta;
  r.wrench_base = out_.wrench_base;
  r.wrench_measured_base = out_.wrench_measured_base;
  r.status = out_.status;
  if (out_.status == CycleStatus::kForceFault || static_cast<int>(out_.status) < 0) fault_pending_ = true;
  if (static_cast<int>(out_.status) < 0) {
    ++counters_.invalid_cycles;
    r.q_command = r.q_nominal;
    r.tcp_correction_m.setZero();
    return Verdict::kInvalid;
  }

  // 3-6: the command, its step limit, the wire's rounding, the guard.
  if (limits_.form == CommandForm::kTcpOffset) {
    form_tcp_offset();
    r.q_command = r.q_feedback;
    r.tcp_correction_m = offset_m_;
    if (!guard(nullptr)) return Verdict::kGuard;
    return Verdict::kSend;
  }
  if (limits_.form == CommandForm::kJointTarget) {
    reference_ = r.q_nominal + r.q_blend;
  } else {
    reference_.setZero();
  }
  form_joint_command(reference_);
  r.q_command = limits_.form == CommandForm::kJointTarget ? command_ : JointVector(r.q_nominal + command_);
  r.tcp_correction_m = -out_.tcp_deflection_base_m;  // what the correction moves the TCP by
  if (!guard(&reference_)) return Verdict::kGuard;
  return Verdict::kSend;
}

void LinkCycle::form_joint_command(const JointVector& reference) noexcept {
  command_ = reference - out_.dtheta;
  if (have_previous_) {
    // The per-cycle step limit: a change beyond it is scaled back as a whole (its direction kept).
    double ratio = 0.0;
    for (int j = 0; j < command_.size(); ++j) {
      ratio = std::max(ratio, std::abs(command_[j] - previous_command_[j]) / limits_.joint_step_rad[j]);
    }
    if (ratio > 1.0) {
      command_ = previous_command_ + (command_ - previous_command_) / ratio;
      record_.step_limited = true;
      ++counters_.step_limited;
    }
  }
  hold_near_last_sent();
  for (int j = 0; j < command_.size(); ++j) command_[j] = limits_.round(command_[j]);
}

void LinkCycle::form_tcp_offset() noexcept {
  offset_m_ = -out_.tcp_deflection_base_m;  // the whole offset, never an increment
  if (have_previous_) {
    const double step = (offset_m_ - previous_offset_m_).norm();
    if (step > limits_.tcp_step_m) {
      offset_m_ = previous_offset_m_ + (offset_m_ - previous_offset_m_) * (limits_.tcp_step_m / step);
      record_.step_limited = true;
      ++counters_.step_limited;
    }
  }
  hold_near_last_sent();
}

// The final guard, in the form the wire carries: the bound against the nominal, the step from the
// previous command (and from the last one sent, after a re-anchor without a silence).
bool LinkCycle::guard(const JointVector* reference) noexcept {
  return limits_.form == CommandForm::kTcpOffset ? guard_tcp_offset() : guard_joints(*reference);
}

bool LinkCycle::guard_tcp_offset() noexcept {
  LinkCycleRecord& r = record_;
  r.deviation_m = offset_m_.norm();
  r.step_m = have_previous_ ? (offset_m_ - previous_offset_m_).norm() : 0.0;
  r.step_fraction = r.step_m / limits_.tcp_step_m;
  if (!offset_m_.allFinite()) return refuse("the TCP offset is not finite: nothing sent");
  if (r.deviation_m > limits_.tcp_bound_m * kRel + 1e-12) {
    return refuse("the TCP offset %.6f mm is beyond the bound %.6f mm: nothing sent", r.deviation_m * 1e3,
                  limits_.tcp_bound_m * 1e3);
  }
  if (r.step_m > limits_.tcp_step_m * kRel + 1e-12) {
    return refuse("the TCP offset moved %.6f mm in one cycle, beyond the step limit %.6f mm: nothing sent",
                  r.step_m * 1e3, limits_.tcp_step_m * 1e3);
  }
  if (hold_last_sent_) {
    const double from_sent = (offset_m_ - last_sent_offset_m_).norm();
    r.step_m = std::max(r.step_m, from_sent);
    if (from_sent > limits_.tcp_step_m * kRel + 1e-12) {
      return refuse(
          "re-anchored without a silence, the TCP offset would move %.6f mm from the last offset sent, beyond the "
          "step limit %.6f mm: nothing sent",
          from_sent * 1e3, limits_.tcp_step_m * 1e3);
    }
  }
  r.step_fraction = r.step_m / limits_.tcp_step_m;
  return true;
}

bool LinkCycle::guard_joints(const JointVector& reference) noexcept {
  LinkCycleRecord& r = record_;
  double fraction = 0.0;
  for (int j = 0; j < command_.size(); ++j) {
    const double c = command_[j];
    if (!std::isfinite(c)) return refuse("joint %d of the command is not finite: nothing sent", j + 1);
    const double res = limits_.resolution_rad(c);
    const double deviation = std::abs(c - reference[j]);
    r.deviation_rad = std::max(r.deviation_rad, deviation);
    if (deviation > limits_.joint_bound_rad * kRel + res + 1e-12) {
      return refuse("joint %d of the command is %.6f deg from the nominal, beyond the bound %.6f deg: nothing sent",
                    j + 1, rad_to_deg(deviation), rad_to_deg(limits_.joint_bound_rad));
    }
    if (have_previous_) {
      const double step = std::abs(c - previous_command_[j]);
      r.step_rad = std::max(r.step_rad, step);
      fraction = std::max(fraction, step / limits_.joint_step_rad[j]);
      if (step > limits_.joint_step_rad[j] * kRel + 2.0 * res + 1e-12) {
        return refuse(
            "joint %d of the command moved %.6f deg in one cycle, beyond the step limit %.6f deg: nothing sent", j + 1,
            rad_to_deg(step), rad_to_deg(limits_.joint_step_rad[j]));
      }
    }
    if (hold_last_sent_) {
      const double from_sent = std::abs(c - last_sent_[j]);
      r.step_rad = std::max(r.step_rad, from_sent);
      fraction = std::max(fraction, from_sent / limits_.joint_step_rad[j]);
      if (from_sent > limits_.joint_step_rad[j] * kRel + 2.0 * res + 1e-12) {
        return refuse(
            "re-anchored without a silence, joint %d of the command would move %.6f deg from the last command sent, "
            "beyond the step limit %.6f deg: nothing sent",
            j + 1, rad_to_deg(from_sent), rad_to_deg(limits_.joint_step_rad[j]));
      }
    }
  }
  r.deviation_m = out_.tcp_correction_m;
  if (!(out_.tcp_correction_m <= limits_.tcp_bound_m * kRel + 1e-12)) {
    return refuse("the correction moves the TCP by %.6f mm, beyond the bound %.6f mm: nothing sent",
                  out_.tcp_correction_m * 1e3, limits_.tcp_bound_m * 1e3);
  }
  step_fraction_ = r.step_fraction = fraction;
  return true;
}

bool LinkCycle::refuse(const char* format, ...) noexcept {
  va_list args;
  va_start(args, format);
  std::vsnprintf(guard_message_.data(), guard_message_.size(), format, args);
  va_end(args);
  ++counters_.guard_trips;
  fault_pending_ = true;
  return false;
}

void LinkCycle::finish(bool sent, double compute_s, double answer_s) noexcept {
  record_.replied = sent;
  record_.compute_s = compute_s;
  record_.answer_s = answer_s;
  if (sent) {
    ++stats_.sent;
    hold_last_sent_ = false;
    if (limits_.form == CommandForm::kTcpOffset) {
      previous_offset_m_ = last_sent_offset_m_ = offset_m_;
      stats_.max_step_m = std::max(stats_.max_step_m, record_.step_m);
      stats_.max_step_fraction = std::max(stats_.max_step_fraction, record_.step_m / limits_.tcp_step_m);
    } else {
      previous_command_ = last_sent_ = command_;
      stats_.max_deviation_rad = std::max(stats_.max_deviation_rad, record_.deviation_rad);
      stats_.max_step_rad = std::max(stats_.max_step_rad, record_.step_rad);
      stats_.max_step_fraction = std::max(stats_.max_step_fraction, step_fraction_);
      if (limits_.form == CommandForm::kJointTarget) {
        stats_.max_program_deviation_rad =
            std::max(stats_.max_program_deviation_rad, (command_ - record_.q_nominal).cwiseAbs().maxCoeff());
      }
    }
    stats_.max_deviation_m = std::max(stats_.max_deviation_m, record_.deviation_m);
    have_previous_ = true;
    last_dtheta_ = out_.dtheta;
  }
  history_.record(record_);
}

void LinkCycle::sent(double compute_s, double answer_s) noexcept { finish(true, compute_s, answer_s); }

void LinkCycle::not_sent(double compute_s) noexcept {
  finish(false, compute_s, std::numeric_limits<double>::quiet_NaN());
}

}  // namespace deflex
