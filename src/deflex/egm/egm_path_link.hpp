// ABB EGM path correction (RAPID: EGMActMove + EGMMoveL/EGMMoveC): the controller runs its own
// programmed path and, at its path-correction rate, asks for a correction; deflex answers each
// EgmRobot with an EgmSensorPathCorr carrying the whole current TCP position correction (an absolute
// offset, never an increment, so nothing accumulates), expressed in the correction frame the RAPID
// program declared, with its age. The nominal deflex holds is "no offset": what it sends is bounded
// by the TCP bound, and its change from one answer to the next by the TCP rate bound times the
// period (the link cycle's step limit), so a stale force ramps the offset out over several answers.
// A new session on the controller (a restart of its sequence, or a message after the restart
// silence) starts its correction afresh from zero offset, and so does deflex's. Orientation cannot
// be corrected in this mode; the link reports the rotation the model predicts so the user sees when
// it matters. The controller's own state ends the session: motors off (a stop), EGM no longer
// running after it ran (EGMStop: the planned end; an error: a stop).
#pragma once

#include <chrono>

#include "deflex/egm/egm_receiver.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/online/delay_estimator.hpp"

namespace deflex {

/// The frame the correction is expressed in (the frame EGMActMove is given).
enum class PathCorrFrame {
  kTool,    ///< the robot model's tool frame (EGMActMove egmID, tool.tframe: ABB's examples)
  kFlange,  ///< tool0
  kPath,    ///< path coordinates: x along the direction of travel, y = z_tool x x, z = x x y
};
[[nodiscard]] const char* to_string(PathCorrFrame f);
/// "tool", "flange" or "path"; throws InputError otherwise.
[[nodiscard]] PathCorrFrame parse_path_corr_frame(const std::string& name);

struct EgmPathLinkConfig {
  EgmReceiverConfig receiver;
  PathCorrFrame frame = PathCorrFrame::kTool;
  LinkStopRules stop;
  /// Rotation of the TCP the model predicts above which the status says it is left uncorrected.
  double rotation_warning_rad = 1e-4;
  /// Predictive strategy: latency of the controller's correction channel beyond the servo delay the
  /// link measures (deflex cannot observe it; take it from the RobotWare in use). s.
  double correction_latency_s = 0.0;
  std::size_t history_cycles = 1000;
  double initial_delay_s = 0.05;
  void validate() const;
};

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class EgmPathLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link. Throws InputError.
  EgmPathLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport,
              const Clock& clock, const EgmPathLinkConfig& config = {});
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  EgmPathLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport,
              const Clock&& clock, const EgmPathLinkConfig& config = {}) = delete;

  LinkPollResult poll(double timeout_s) noexcept override;
  [[nodiscard]] const char* name() const override { return "egm-path"; }

  [[nodiscard]] const DelayEstimator& delay() const { return delay_; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  [[nodiscard]] std::string protocol_summary() const override;
  /// Cycles whose predicted rotation exceeded the warning threshold, and the largest one (rad).
  [[nodiscard]] std::uint64_t rotation_warnings() const { return rotation_warnings_; }
  [[nodiscard]] double max_rotation_rad() const { return max_rotation_rad_; }
  /// The correction period the controller asks at (s, measured; 0 before two messages).
  [[nodiscard]] double period_s() const { return cycle_.motion().period_s(); }
  [[nodiscard]] const EgmPathLinkConfig& config() const { return config_; }

 private:
  bool correction_frame(const JointVector& q_feedback, Matrix3& base_R_frame) noexcept;
  bool controller_state(const EgmRobotMessage& m) noexcept;
  // poll()'s stages after a message was taken.
  void track_motion(double now, bool has_planned) noexcept;
  LinkPollResult answer(double now, std::uint32_t seqno, bool session_start,
                        std::chrono::steady_clock::time_point t_read) noexcept;
  void note_sent_offset(const Vector3& correction) noexcept;

  EgmPathLinkConfig config_;
  EgmReceiver receiver_;
  DelayEstimator delay_;
  bool egm_ran_ = false;

  JointVector feedback_, planned_;
  /// The joint motion the last offset sent asks of the controller (the arm's joints move by it,
  /// orientation held): the delay is measured between planned + this and the feedback, which carries
  /// the applied offset.
  JointVector sent_offset_joints_;
  JointVector reference_;
  JointVector previous_path_q_;  // the joints the direction of travel was last taken from
  Vector3 travel_direction_ = Vector3::Zero();
  bool have_direction_ = false;
  Matrix3 last_frame_ = Matrix3::Identity();  // the correction frame last known (kept when it cannot be formed)
  bool have_frame_ = false;
  std::uint64_t rotation_warnings_ = 0;
  double max_rotation_rad_ = 0.0;
  EgmPathCorrMessage reply_;
  std::vector<unsigned char> tx_;
  std::uint32_t reply_seq_ = 0;
  Jacobian jac_;
};

}  // namespace deflex
