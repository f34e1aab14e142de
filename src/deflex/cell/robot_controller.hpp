// The simulated robot controller as the servo sees it: every servo tick it gives the motor-side joint
// position the arm is driven to (the true robot adds its elasticity), and meanwhile talks to whatever
// external sensor it talks to, as the real controller would. Three kinds:
//   ProgramController             runs its own robot program (RAPID MoveAbsJ / KRL PTP through points)
//   EgmPositionGuidanceController follows the absolute targets an EGM sensor streams (egm_position_controller.hpp)
//   EgmPathCorrectionController   runs its program and applies an EGM sensor's path offsets (egm_path_controller.hpp)
#pragma once

#include <memory>

#include "deflex/paths/joint_trajectory.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (the simulation's), for every controller.
class RobotController {
 public:
  virtual ~RobotController() = default;
  /// Advances to t_s (once per servo tick, increasing) and returns the motor-side joints (rad) the
  /// drives are commanded to.
  virtual const JointVector& tick(double t_s) = 0;
  /// The motors' encoders after the tick (rad): where the drives got to, behind their command by the
  /// servo's following error. What the controller reports as the robot's position from then on.
  virtual void encoders(const JointVector& q_motor_rad) { (void)q_motor_rad; }
  [[nodiscard]] virtual const char* name() const = 0;

 protected:
  RobotController() = default;
  RobotController(const RobotController&) = default;
  RobotController& operator=(const RobotController&) = default;
};

/// Runs a program of its own: the joint trajectory's interpolation, exactly, each servo tick.
/// Thread safety: one thread at a time; the program it shares is immutable.
class ProgramController final : public RobotController {
 public:
  explicit ProgramController(std::shared_ptr<const JointTrajectory> program) : program_(std::move(program)) {
    q_ = program_->points().front();
  }
  const JointVector& tick(double t_s) override {
    program_->sample(t_s, q_);
    return q_;
  }
  [[nodiscard]] const char* name() const override { return "robot program"; }

 private:
  std::shared_ptr<const JointTrajectory> program_;
  JointVector q_;
};

}  // namespace deflex::cell
