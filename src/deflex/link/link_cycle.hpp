// The one cycle every controller link runs between decoding a controller message and encoding its
// answer, written once:
//   1. the strategy prepares the compensator's input (hybrid, predictive ... online_strategy.hpp);
//   2. the compensator gives the bounded, rate-limited correction dtheta (online_compensator.hpp);
//   3. the command is formed against the nominal deflex holds: absolute joints nominal - dtheta
//      (position guidance, streaming), a whole joint offset -dtheta (RSI), a whole TCP offset
//      -J_p dtheta (EGM path correction);
//   4. the per-cycle step limit holds the command's change from the previous command sent (a change
//      beyond it is scaled back as a whole, and counted);
//   5. the command is rounded to what the wire carries (float32 radians, decimals of a degree);
//   6. the final guard checks the rounded values: within the bound of the nominal and within the step
//      limit of the previous command. A command that fails is not sent; the link stops (kSafety);
//   7. the record goes to the history ring.
// A session start anchors the step reference to what the controller holds then (its reference, or
// zero offset for a controller that starts its correction afresh), so no first command steps. Unless
// the controller fell silent first (its previous session then ended on its own), it may still hold
// what deflex last sent: the first command after such a re-anchor is held within the step limit of
// both, and the guard refuses one that is not (the links stop when no command can be: reanchor_gap()).
// The limits are derived once, at the session's start (command_limits), from the bounds, the rate
// bound, the period, the program's own speeds and the ramp-in: the loop only computes and checks.
// Never allocates, locks or throws after construction.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <string>

#include "deflex/link/feedback_motion.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/link/link_history.hpp"
#include "deflex/link/link_record.hpp"
#include "deflex/online/cycle_types.hpp"
#include "deflex/online/force_sample.hpp"

namespace deflex {

// The cycle drives these by reference; their headers are the .cpp files' business.
class OnlineCompensator;
class OnlineStrategy;
class CorrectionSmoother;

/// What a link sends the controller, and so what its command is measured against.
enum class CommandForm : int {
  kJointTarget = 0,  ///< absolute joints: nominal - dtheta (egm-joint, simple-message); the nominal moves
  kJointOffset = 1,  ///< the whole joint offset from the controller's own program: -dtheta (rsi); nominal 0
  kTcpOffset = 2,    ///< the whole TCP offset from the controller's own path: -J_p dtheta (egm-path); nominal 0
};
[[nodiscard]] const char* to_string(CommandForm f);

/// How the wire carries joint values: the guard checks the values as the controller will read them.
enum class WireRounding : int {
  kExact = 0,        ///< doubles (EGM's protobuf)
  kFloat32 = 1,      ///< float32 radians (simple message)
  kDecimalsDeg = 2,  ///< degrees as text with `decimals` decimals (RSI)
  kFloat32Deg = 3,   ///< float32 degrees (FANUC Stream Motion version 1)
};

/// The two invariants on what goes on the wire, stated once at the session's start.
struct CommandLimits {
  CommandForm form = CommandForm::kJointTarget;
  /// Joint forms: |command_i - nominal_i| (targets) or |offset_i| (offsets), rad.
  double joint_bound_rad = 0.0;
  /// |TCP translation of the correction|, m (every form; the TCP form's offset itself).
  double tcp_bound_m = 0.0;
  /// Joint forms: |command_i(k) - command_i(k-1)| between consecutive commands sent, rad.
  JointVector joint_step_rad;
  /// TCP form: |offset(k) - offset(k-1)|, m.
  double tcp_step_m = 0.0;
  WireRounding rounding = WireRounding::kExact;
  int decimals = 6;  ///< kDecimalsDeg
  /// The wire's rounding of a joint value of magnitude |v| (rad): allowed on top of bound and step.
  [[nodiscard]] double resolution_rad(double v) const noexcept;
  /// Rounds a joint value (rad) as the wire carries it.
  [[nodiscard]] double round(double v) const noexcept;
  /// Throws InputError naming what is wrong (a limit not > 0, a step limit of the wrong size, a step
  /// limit larger than the bound for an offset form).
  void validate(int dof) const;
  /// "bound 0.5 deg a joint, 5 mm at the TCP; step 0.012..0.41 deg a cycle" (for the start-up line).
  [[nodiscard]] std::string describe() const;
};

/// The limits a link runs under, derived once at the session's start (ruckig's validate-first):
///   joint target: bound = max_joint_correction; step_i = period (program peak speed_i + the ramp-in
///     blend's peak speed + the correction's rate bound), the program's speeds from `program`;
///   joint offset: bound = max_joint_correction; step_i = period x the rate bound;
///   TCP offset: bound = max_tcp_correction; step = period x the TCP rate bound.
/// `program` and `stream` are required for the joint target form. Throws InputError when the options
/// cannot work: an offset form whose step per cycle (the rate bound times the period) is larger than
/// its bound, naming the options.
[[nodiscard]] CommandLimits command_limits(CommandForm form, const OnlineConfig& online, int dof,
                                           const JointTrajectory* program = nullptr,
                                           const JointStreamConfig* stream = nullptr);

/// What a link decoded, for one cycle.
struct CycleRequest {
  double t_s = 0.0;
  std::uint64_t sequence = 0;
  double program_time_s = 0.0;
  /// Joint target: the program (un-blended); offset forms: the controller's planned or setpoint joints
  /// (recorded; the nominal of an offset is zero).
  const JointVector* nominal = nullptr;
  const JointVector* blend = nullptr;     ///< joint target: the blend offset (null: none)
  const JointVector* feedback = nullptr;  ///< where the controller says the arm is
  const JointVector* target = nullptr;    ///< the configuration the correction is for
  double delay_s = 0.0;                   ///< the link's measured delay (strategy and record)
  double lead_s = 0.0;                    ///< how far ahead of the feedback the target is (strategy)
  bool hold = false;                      ///< the link cannot trust this cycle: the correction ramps to zero
  bool session_start = false;             ///< the first cycle of a session (recorded)
  LinkArrival arrival;
};

/// What the cycles have sent so far, measured on the wire values.
struct CycleStats {
  std::uint64_t cycles = 0, sent = 0;
  double max_deviation_rad = 0.0;  ///< largest |command - (nominal + blend)| of any joint (joint forms)
  double max_deviation_m = 0.0;    ///< largest TCP correction sent
  /// Joint target: the largest |command - program| of any joint, the blend included (what the status
  /// line reports next to the bound: the blend is not hidden).
  double max_program_deviation_rad = 0.0;
  double max_step_rad = 0.0;  ///< largest step between consecutive commands of any joint (joint forms)
  double max_step_m = 0.0;    ///< largest step of the TCP offset (TCP form)
  /// max_step_rad as a fraction of that joint's step limit, and the same for the TCP (<= 1 on the wire).
  double max_step_fraction = 0.0;
};

/// Thread safety: one thread at a time (the link's), together with the compensator and strategy it
/// drives.
class LinkCycle {
 public:
  enum class Verdict : int {
    kSend = 0,      ///< the command passed the guard: encode joint_command() or tcp_offset_m() and send
    kInvalid = -1,  ///< the compensator refused the input (no command)
    kGuard = -2,    ///< the final guard refused the command: guard_message() says why; send nothing
  };

  /// Every reference must outlive the cycle. Throws InputError on limits that do not fit the robot.
  LinkCycle(OnlineCompensator& compensator, OnlineStrategy& strategy, const CommandLimits& limits,
            std::size_t history_cycles, LinkCounters& counters);

  /// The force source each cycle reads (step 2): the session's, handed here before the first cycle;
  /// null (the default) when samples are pushed into the compensator directly. It must outlive the
  /// cycle. The link never touches it: no link's code depends on where the force comes from.
  void read_force_from(ForceSource* force) noexcept { force_ = force; }

  /// One cycle (steps 1-6 above). Never allocates, locks or throws.
  Verdict run(const CycleRequest& request) noexcept;
  /// After kSend: the joint command as the wire carries it (joint target: absolute joints; joint
  /// offset: the offset, -dtheta rounded).
  [[nodiscard]] const JointVector& joint_command() const { return command_; }
  /// After kSend, the TCP form: the offset in the base frame (m).
  [[nodiscard]] const Vector3& tcp_offset_m() const { return offset_m_; }
  [[nodiscard]] const CycleOutput& output() const { return out_; }
  /// The cycle's answer went out: it becomes the step reference; the record is kept. `answer_s`: from
  /// the message's arrival at the host to now (NaN when unknown).
  void sent(double compute_s, double answer_s = std::numeric_limits<double>::quiet_NaN()) noexcept;
  /// The cycle's answer did not go out (guard, encoding, a full socket): the record is kept.
  void not_sent(double compute_s) noexcept;
  /// A session starts with the controller holding `q` (joint target: its reference; joint offset:
  /// the offset it applies): the next command is measured from it. `after_silence`: the controller was
  /// silent before (its previous session ended on its own); otherwise the next command is also held
  /// within the step limit of the last command sent.
  void anchor_joints(const JointVector& q, bool after_silence) noexcept;
  /// A session starts with the controller applying `offset_m` (TCP form); `after_silence` as above.
  void anchor_tcp(const Vector3& offset_m, bool after_silence) noexcept;
  /// The controller starts its correction afresh (a new RSI or path-correction session): the
  /// compensator starts from zero correction, and the step reference is zero offset; `after_silence`
  /// as above.
  void restart_from_zero(bool after_silence) noexcept;
  /// How far a re-anchor on `q` (joint forms) or `offset_m` (TCP form) is from the last command sent,
  /// in per-cycle step limits (the largest joint's); 0 before anything was sent. Beyond 2 no command can
  /// be within the step limit of both.
  [[nodiscard]] double reanchor_gap(const JointVector& q) const noexcept;
  [[nodiscard]] double reanchor_gap(const Vector3& offset_m) const noexcept;

  /// The correction passes through `smoother` before the command is formed (controllers that check
  /// the stream's acceleration and jerk: FANUC's Stream Motion); null: none. It must outlive the
  /// cycle; a restart from zero resets it. The joint forms only.
  void shape_with(CorrectionSmoother* smoother) noexcept { smoother_ = smoother; }

  /// The TCP rotation the model predicts and the link cannot correct this cycle (recorded; rad).
  void note_uncorrected_rotation(double rad) noexcept { record_.rotation_uncorrected_rad = rad; }
  [[nodiscard]] const char* guard_message() const { return guard_message_.data(); }
  [[nodiscard]] const LinkCycleRecord& record() const { return record_; }
  [[nodiscard]] const LinkHistory& history() const { return history_; }
  [[nodiscard]] const CycleStats& stats() const { return stats_; }
  [[nodiscard]] const CommandLimits& limits() const { return limits_; }
  [[nodiscard]] const OnlineCompensator& compensator() const { return comp_; }
  [[nodiscard]] OnlineCompensator& compensator() { return comp_; }
  [[nodiscard]] const OnlineStrategy& strategy() const { return strategy_; }
  /// The arm's velocity from the feedback, for the links that correct a program the controller runs
  /// (the predictive strategy's target there): the link observes each cycle's feedback into it.
  [[nodiscard]] FeedbackMotion& motion() { return motion_; }
  [[nodiscard]] const FeedbackMotion& motion() const { return motion_; }
  /// The target of this cycle: `from` (the feedback or the planned joints), led by `lead_s` at the
  /// feedback's velocity when the strategy is the predictive one.
  [[nodiscard]] const JointVector& lead_target(const JointVector& from, double lead_s) noexcept;
  /// The last joint command sent (joint forms; valid once has_sent()).
  [[nodiscard]] const JointVector& last_command() const { return previous_command_; }
  [[nodiscard]] bool has_sent() const { return stats_.sent > 0; }
  /// The correction now (rad): what the controller's last command was corrected by.
  [[nodiscard]] const JointVector& correction() const { return last_dtheta_; }
  [[nodiscard]] bool fault_pending() const { return fault_pending_; }
  void clear_fault() { fault_pending_ = false; }

 private:
  void form_joint_command(const JointVector& nominal_plus_blend) noexcept;
  void form_tcp_offset() noexcept;
  void hold_near_last_sent() noexcept;
  bool guard(const JointVector* nominal_plus_blend) noexcept;
  bool guard_tcp_offset() noexcept;
  bool guard_joints(const JointVector& nominal_plus_blend) noexcept;
  static constexpr double kRel = 1.0 + 1e-9;  // the guard's limits hold to rounding
  bool refuse(const char* format, ...) noexcept __attribute__((format(printf, 2, 3)));
  void finish(bool sent, double compute_s, double answer_s) noexcept;

  OnlineCompensator& comp_;
  OnlineStrategy& strategy_;
  ForceSource* force_ = nullptr;
  CorrectionSmoother* smoother_ = nullptr;
  CommandLimits limits_;
  LinkCounters& counters_;
  LinkHistory history_;
  FeedbackMotion motion_;
  CycleInput input_;
  CycleOutput out_;
  JointVector command_, previous_command_, reference_, last_dtheta_;
  JointVector last_sent_;  // the last joint command that went on the wire (no anchor replaces it)
  Vector3 offset_m_ = Vector3::Zero(), previous_offset_m_ = Vector3::Zero(), last_sent_offset_m_ = Vector3::Zero();
  bool have_previous_ = false;
  bool hold_last_sent_ = false;  // re-anchored without a silence: the next command steps from both
  bool fault_pending_ = false;
  double step_fraction_ = 0.0;  // this cycle's largest step over its limit
  LinkCycleRecord record_;
  CycleStats stats_;
  std::array<char, 256> guard_message_{};
};

}  // namespace deflex
