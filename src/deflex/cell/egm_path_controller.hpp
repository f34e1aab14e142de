// The controller side of ABB EGM path correction (EGMActMove + EGMMoveL/EGMMoveC), as the real
// controller behaves, never more kindly:
//   - it runs its own program; every path_corr_period_s (EGMActMove \SampleRate) it sends an EgmRobot
//     with the motor-side joints as feedback and its programmed joints as "planned";
//   - each EgmSensorPathCorr carries the whole current offset (never an increment) in the correction
//     frame the program declared (tool, tool0 or path coordinates); the controller takes the newest,
//     applies it after its dead time, smoothed, as a TCP translation (orientation is not corrected),
//     resolving it into joints with its own kinematic model.
// It knows nothing of deflex: only the wire format, over a datagram transport.
#pragma once

#include <memory>
#include <vector>

#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/model/kinematics.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (the simulation's), with its transport.
class EgmPathCorrectionController final : public RobotController {
 public:
  /// `kinematics`: the controller's own model (nominal kinematics and the tool). `program`: the path
  /// it runs. Throws InputError for an unknown correction frame.
  EgmPathCorrectionController(const ControllerConfig& config, const RobotModel& kinematics,
                              std::shared_ptr<const JointTrajectory> program, DatagramTransport& transport,
                              const DatagramAddress& sensor);

  const JointVector& tick(double t_s) override;
  void encoders(const JointVector& q_motor_rad) override;
  [[nodiscard]] const char* name() const override { return "EGM path correction"; }
  [[nodiscard]] const EgmControllerCounters& counters() const { return counters_; }
  /// The TCP offset applied now (m, base frame).
  [[nodiscard]] const Vector3& applied_offset_m() const { return applied_m_; }
  /// A new path-correction session from the next message on (EGMActMove again): the sequence starts
  /// again and the correction with it, from no offset (offsets already read are dropped).
  void restart();

 private:
  enum class Frame { kTool, kFlange, kPath };
  ControllerConfig config_;
  RobotModel model_;
  Workspace ws_;
  Jacobian jac_;
  std::shared_ptr<const JointTrajectory> program_;
  DatagramTransport& transport_;
  DatagramAddress sensor_;
  Frame frame_ = Frame::kTool;
  EgmCodec codec_;
  std::vector<unsigned char> buffer_;
  EgmRobotMessage robot_;
  EgmPathCorrMessage answer_;
  // Offsets read but not yet in effect (dead time), in the correction frame.
  struct Pending {
    double due_s = 0.0;
    Vector3 offset_frame_m = Vector3::Zero();
  };
  std::vector<Pending> pending_;
  std::size_t pending_head_ = 0, pending_count_ = 0;
  Vector3 active_frame_m_ = Vector3::Zero();
  Vector3 applied_m_ = Vector3::Zero();
  Vector3 direction_ = Vector3::UnitX();
  JointVector encoders_;  ///< the last encoder reading: the feedback it reports
  bool have_encoders_ = false;
  JointVector planned_, planned_velocity_, position_;
  double last_t_s_ = 0.0, next_send_s_ = 0.0;
  std::uint32_t seqno_ = 0;
  EgmControllerCounters counters_;
};

}  // namespace deflex::cell
