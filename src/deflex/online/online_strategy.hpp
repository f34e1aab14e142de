// The online strategies a controller link can run, as deployable library features
// (deflex online --strategy):
//   online      the paper's (Figure 3): the measured, conditioned wrench, as it is;
//   hybrid      an offline-compensated program is the nominal, and only measured minus modelled force
//               is corrected online, the model evaluated at the pose the controller reports;
//   predictive  latency compensation: the wrench predicted where the command will be executed, one
//               measured delay ahead of the pose the force was measured at (by the force model's
//               change when one is given, else along the measured wrench's own slope).
//   none        no correction: the link streams the nominal only (the reference runs of an
//               experiment, unloaded and uncompensated, through the same link).
// Each strategy fills the compensator's CycleInput; nothing here knows of a simulator: it sees only
// the configurations a link has (the nominal it holds, the feedback the controller sends).
#pragma once

#include <string>

#include "deflex/force/force_model.hpp"
#include "deflex/model/frame_cache.hpp"
#include "deflex/online/online_compensator.hpp"

namespace deflex {

enum class StrategyKind { kOnline, kHybrid, kPredictive, kNone };
[[nodiscard]] const char* to_string(StrategyKind kind);
/// "online", "hybrid", "predictive" or "none"; throws InputError naming the text otherwise.
[[nodiscard]] StrategyKind parse_strategy(const std::string& name);

/// Why a strategy could not prepare a cycle (the link then sends no correction this cycle).
enum class StrategyStatus : int {
  kOk = 0,
  kModelForceUnavailable = -1,  ///< the force model has no value at this pose (degenerate geometry)
  /// A joint vector the strategy needs has the wrong count or a value that is not finite (the
  /// compensator refuses the same cycle with CycleStatus::kInvalidInput).
  kInvalidInput = -2,
};

/// Thread safety: one thread at a time (the cycle's frames it is handed); the force model it reads may
/// be shared.
class OnlineStrategy {
 public:
  /// `model` gives the joint count (the frames come from the cycle: prepare()). `force_model` (not owned, may be
  /// null; must outlive the strategy): required by hybrid, used by predictive when given. Throws
  /// InputError when hybrid has none, or when the model cannot give a wrench from a pose alone (a
  /// path-indexed table).
  OnlineStrategy(const RobotModel& model, StrategyKind kind, const ForceModel* force_model);

  /// Fills in.wrench_offset_base and in.wrench_lead_s for one cycle. `q_feedback`: where the arm is
  /// (the pose the measured force belongs to); `q_target`: the configuration the command is for;
  /// `delay_s`: how long after it is sent a command shows in the feedback (measured by the link);
  /// `filter_lag_s`: the force low-pass's own lag. Never allocates or throws: a q_feedback (hybrid,
  /// predictive with a model) or q_target (predictive with a model) that does not hold one finite value
  /// a joint gives kInvalidInput, in Release too. `frames`: the cycle's (the compensator's), so the
  /// kinematics at the feedback and the target run once a cycle for the strategy and the compensator.
  StrategyStatus prepare(CycleInput& in, const JointVector& q_feedback, const JointVector& q_target, double delay_s,
                         double filter_lag_s, FrameCache& frames) noexcept;

  [[nodiscard]] StrategyKind kind() const { return kind_; }
  [[nodiscard]] const ForceModel* force_model() const { return force_; }
  /// The model wrench at the feedback pose in the last prepare (base frame, at the WAP).
  [[nodiscard]] const Wrench& last_model_wrench() const { return model_wrench_fb_; }

 private:
  [[nodiscard]] bool joints_usable(const JointVector& q) const noexcept;
  bool model_wrench_at(FrameCache& frames, const JointVector& q, Wrench& out) noexcept;

  int dof_;
  StrategyKind kind_;
  const ForceModel* force_;
  Wrench model_wrench_fb_ = Wrench::Zero();
};

}  // namespace deflex
