// The simulated cell's true robot: what the compensators never see. IRB6700 kinematics with small
// seeded DH errors, a true joint stiffness (coupled between joints 2 and 3) on gears that harden with
// torque, stiffness that depends on the joints' motion, the servos' following and yielding, forearm
// and upper-arm bending, the base's tilt, the force sensor as an elastic element between flange and
// end effector, and direction-dependent lost motion. The deflection is solved at the deflected
// configuration (fixed point).
#pragma once

#include <cstdint>
#include <memory>

#include "deflex/cell/cell_config.hpp"
#include "deflex/model/kinematics.hpp"

namespace deflex::cell {

/// Lost motion of one joint as a play operator with saturation: the joint torque must exceed
/// `torque_nm` in the new direction before the joint travels across its band of +-half_width_rad,
/// so the offset depends on the sign of the torque and on its history (CW and CCW laps differ).
/// Thread safety: one thread at a time (update() changes its state): part of one run's
/// TrueRobotState.
struct LostMotion {
  double half_width_rad = 0.0;
  double torque_nm = 1.0;
  double state = 0.0;  ///< play-operator output in torque units / torque_nm, clamped to [-1, 1] on use
  /// Advances with the joint torque and returns the angular offset (rad).
  double update(double joint_torque_nm);
  [[nodiscard]] double offset_rad() const;
};

/// Torque-dependent stiffness of one gear (hardening reducer): the tangent compliance at the total
/// joint torque x is c (1 + softening exp(-|x|/torque_nm)), so the gear is (1 + softening) times
/// softer near zero torque than at large torque. equivalent_torque(x) is the torque a linear gear of
/// compliance c would need for the same deflection from zero torque:
///   H(x) = x + softening torque_nm sign(x) (1 - exp(-|x|/torque_nm)).
struct GearHardening {
  double softening = 0.0;
  double torque_nm = 1.0;
  [[nodiscard]] double equivalent_torque(double total_torque_nm) const;
  /// Equivalent torque of a process torque `tau_nm` on top of the static preload (gravity).
  [[nodiscard]] double increment(double preload_nm, double tau_nm) const {
    return equivalent_torque(preload_nm + tau_nm) - equivalent_torque(preload_nm);
  }
};

/// Per-run mutable state of the true robot (one per simulated run).
struct TrueRobotState {
  JointVector q_actual;    ///< last solved configuration (warm start of the next solve)
  JointVector q_cmd_last;  ///< command of the last solve
  JointVector q_motor;     ///< the motors' position at the last solve: the command less the following error
  /// The deflection q_actual - q_motor of the last solve and its change from the one before (the next
  /// solve's starting guess extrapolates it).
  JointVector deflection, deflection_step;
  std::array<LostMotion, kMaxJoints> lost_motion{};
  JointVector gravity_torque_nm;  ///< preload of the lost motion (constant)
  /// The gears' equivalent torque at that preload (constant: every solve's hardening starts from it).
  JointVector gravity_equivalent_nm;
  JointVector torque_lowpass_nm;  ///< the servo's integral action: the process torque it has taken over
  bool have_torque_lowpass = false;
  /// Its gain per tick, 1 - exp(-dt / servo_integral_s), for the tick length it was taken at.
  double torque_lowpass_dt_s = -1.0, torque_lowpass_gain = 0.0;
};

/// Thread safety: immutable once built: one true robot may serve runs on any number of threads,
/// each with its own Workspace and TrueRobotState.
class TrueRobot {
 public:
  /// `sensor_mounted` puts the sensor's height and compliance between flange and end effector.
  /// `seed` draws the per-joint stiffness factors and the DH errors.
  TrueRobot(const CellConfig& config, bool sensor_mounted, std::uint64_t seed);

  /// The nominal model the compensators start from: built-in kinematics, the setup's tool, the
  /// built-in (assumed) stiffness. Nothing of the true robot leaks into it.
  [[nodiscard]] const RobotModel& nominal_model() const { return *nominal_; }
  /// True kinematics with the true diagonal stiffness (for the model-consistent test cell).
  [[nodiscard]] const RobotModel& true_model() const { return *true_; }
  [[nodiscard]] const JointMatrix& joint_compliance() const { return joint_compliance_; }

  [[nodiscard]] TrueRobotState initial_state(const JointVector& q_cmd) const;

  /// Solves the configuration the arm takes when commanded to q_cmd under `wrench_base` (N, Nm at the
  /// TCP, base frame) and returns the TCP position (m, base frame) including the link-bending, base
  /// and sensor displacements. Updates the lost motion and the servos once per call: one call per servo
  /// cycle of `dt_s` (0: a static pose, no motion effects).
  Vector3 solve(Workspace& ws, const JointVector& q_cmd, const Wrench& wrench_base, TrueRobotState& state,
                double dt_s = 0.0) const;

  [[nodiscard]] const CellConfig& config() const { return config_; }
  [[nodiscard]] bool sensor_mounted() const { return sensor_mounted_; }

  /// Cartesian displacement (m) of the TCP from the link and sensor compliances at the current
  /// FK in `ws`: exposed for tests against the cantilever and sensor closed forms.
  [[nodiscard]] Vector3 structural_displacement(const Workspace& ws, const Wrench& wrench_base) const;

  /// The motors' position for a solve to the command `q_cmd` a tick of `dt_s` after `state`'s: the
  /// command less the servo's following error (rad).
  [[nodiscard]] JointVector motor_position(const JointVector& q_cmd, const TrueRobotState& state, double dt_s) const;

  /// The TCP's displacement per unit change of the force at the TCP (m/N, base frame) at the
  /// configuration `q` under `wrench_base` (N, Nm at the TCP, base frame): the joints' compliance
  /// (coupling included) at their gears' torque and with the servo's yield to a fast change, through the
  /// TCP Jacobian, plus the links', the base's and the sensor's. The tangent of solve() without the
  /// motion's scale and the lost motion: what a Newton step needs, not the arm's exact answer. Runs FK
  /// at q in `ws`.
  [[nodiscard]] Matrix3 tcp_force_compliance(Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                                             const TrueRobotState& state) const;

 private:
  CellConfig config_;
  bool sensor_mounted_;
  std::shared_ptr<const RobotModel> nominal_;
  std::shared_ptr<const RobotModel> true_;
  JointMatrix joint_compliance_;
  std::array<GearHardening, kMaxJoints> hardening_{};
  bool hardening_on_ = false;
  double last_d_m_ = 0.0;            ///< wrist centre to flange along the flange z axis
  double upper_arm_length_m_ = 0.0;  ///< joint 2 axis to joint 3 axis
};

/// Flange to TCP of a setup: end effector, plus the sensor's height when it is mounted.
[[nodiscard]] Pose setup_flange_T_tcp(const CellConfig& config, bool sensor_mounted);

}  // namespace deflex::cell
