// The online strategies (see online_strategy.hpp).
#include "deflex/online/online_strategy.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

const char* to_string(StrategyKind kind) {
  switch (kind) {
    case StrategyKind::kOnline:
      return "online";
    case StrategyKind::kHybrid:
      return "hybrid";
    case StrategyKind::kPredictive:
      return "predictive";
    case StrategyKind::kNone:
      return "none";
  }
  return "unknown";
}

StrategyKind parse_strategy(const std::string& name) {
  if (name == "online") return StrategyKind::kOnline;
  if (name == "hybrid") return StrategyKind::kHybrid;
  if (name == "predictive") return StrategyKind::kPredictive;
  if (name == "none") return StrategyKind::kNone;
  throw InputError(fmt::format("strategy '{}' is not online, hybrid, predictive or none", name));
}

OnlineStrategy::OnlineStrategy(const RobotModel& model, StrategyKind kind, const ForceModel* force_model)
    : dof_(model.dof()), kind_(kind), force_(force_model) {
  if (kind_ == StrategyKind::kHybrid && force_ == nullptr) {
    throw InputError("the hybrid strategy needs a force model (the offline program's): give --force");
  }
  if (force_ != nullptr) {
    Wrench probe;
    // Any pose away from the model's singular places: a pose model answers, an indexed one does not.
    Pose far = Pose::Identity();
    far.translation() = Vector3(1e3, 1e3, 1e3);
    if (!force_->wrench_at_pose(far, probe) && !force_->wrench_at_pose(Pose::Identity(), probe)) {
      throw InputError(
          fmt::format("force model '{}' needs a path index; the online strategies need a model of the "
                      "pose (ldbb:..., constant:...)",
                      force_->describe()));
    }
  }
}

bool OnlineStrategy::joints_usable(const JointVector& q) const noexcept {
  // forward_kinematics throws on the wrong count, which would end the program from this noexcept
  // path; the cycle's joints come from the wire each cycle, so nothing at set-up can vouch for them.
  return q.size() == dof_ && q.allFinite();
}

bool OnlineStrategy::model_wrench_at(FrameCache& frames, const JointVector& q, Wrench& out) noexcept {
  const Workspace& ws = frames.at(q);  // q was checked (joints_usable): the kinematics do not throw
  Wrench at_tcp;
  if (!force_->wrench_at_pose(ws.base_T_tcp, at_tcp) || !at_tcp.allFinite()) {
    return false;
  }
  // Force models give the moment about the TCP; the compensator works at the WAP.
  out = moment_moved(at_tcp, ws.base_T_tcp.translation(), ws.base_T_wap.translation());
  return true;
}

StrategyStatus OnlineStrategy::prepare(CycleInput& in, const JointVector& q_feedback, const JointVector& q_target,
                                       double delay_s, double filter_lag_s, FrameCache& frames) noexcept {
  in.wrench_offset_base.setZero();
  in.wrench_lead_s = 0.0;
  in.hold_to_zero = false;
  switch (kind_) {
    case StrategyKind::kNone:
      in.hold_to_zero = true;
      return StrategyStatus::kOk;
    case StrategyKind::kOnline:
      return StrategyStatus::kOk;
    case StrategyKind::kHybrid:
      if (!joints_usable(q_feedback)) return StrategyStatus::kInvalidInput;
      // The offline program already holds the model's part; correct only what the model missed.
      if (!model_wrench_at(frames, q_feedback, model_wrench_fb_)) return StrategyStatus::kModelForceUnavailable;
      in.wrench_offset_base = -model_wrench_fb_;
      return StrategyStatus::kOk;
    case StrategyKind::kPredictive: {
      if (force_ == nullptr) {
        // No model: along the measured wrench's slope, across the link delay and the filter's lag.
        in.wrench_lead_s = delay_s + filter_lag_s;
        return StrategyStatus::kOk;
      }
      // With a model: its change from the pose the force was measured at to the pose the command is
      // for; the filter's lag (time, not pose) along the measured slope.
      if (!joints_usable(q_feedback) || !joints_usable(q_target)) return StrategyStatus::kInvalidInput;
      Wrench at_target;
      if (!model_wrench_at(frames, q_feedback, model_wrench_fb_) || !model_wrench_at(frames, q_target, at_target)) {
        return StrategyStatus::kModelForceUnavailable;
      }
      in.wrench_offset_base = at_target - model_wrench_fb_;
      in.wrench_lead_s = filter_lag_s;
      return StrategyStatus::kOk;
    }
  }
  return StrategyStatus::kOk;
}

}  // namespace deflex
