// The nominal a streaming link holds (ABB EGM position guidance, ROS-Industrial simple message): the
// program deflex streams. The program never comes from the controller's echo: in position guidance
// the controller reports deflex's own last command as "planned", and a reply built on it would
// integrate its own correction.
//   - The program's clock is the controller's consumption, not the wall clock: it moves on by one
//     controller cycle for each answer the controller is given (consumed()). A silence, a stalled PC
//     or a late answer therefore never makes the program run ahead of what the controller has taken,
//     and after any of them the next target is one cycle of the program further on.
//   - A session (the first, and each after a controller restart) starts from what the controller
//     holds, its anchor (its reference, or where the arm is): the offset between the anchor and the
//     command deflex would send (the program less the correction) is blended out (smoothstep) over the
//     ramp time, so the first command equals the anchor and the correction is applied once. The
//     offset must be within the start tolerance on every joint, or the session is refused.
//   - The blend has its own clock (it goes on after the program's end); the end's last point is held.
//   - A planned stop while the program moves (begin_stop(): SIGINT, SIGTERM, a time limit) brings it to
//     a standstill on its own path: the program's clock slows from one period a cycle to none over the
//     ramp (speed factor 1 - smoothstep(t/ramp)), so every joint's speed only falls (within its limits
//     and the per-cycle step limit), its deceleration starts and ends at zero (no jerk spike for a
//     controller that checks it), at most 1.5 x its peak program speed over the ramp, and it stops
//     after half the ramp's length of program time, as a linear ramp would.
#pragma once

#include <cstdint>
#include <memory>

#include "deflex/paths/joint_trajectory.hpp"

namespace deflex {

struct JointStreamConfig {
  double ramp_in_s = 1.0;                    ///< s, blend from the anchor to the program
  double start_tolerance_rad = kPi / 180.0;  ///< the anchor must be this close to the command (1 deg)
  /// Throws InputError on a negative or non-finite value.
  void validate() const;
};

/// Thread safety: one thread at a time, const calls included (sample() writes scratch vectors of
/// its own); the trajectory it shares is immutable.
class JointStream {
 public:
  /// `trajectory` is shared (a long program is not copied). Throws InputError on a bad config.
  JointStream(std::shared_ptr<const JointTrajectory> trajectory, const JointStreamConfig& config);

  /// A session starts with the controller holding `anchor` (rad) while deflex's correction is
  /// `dtheta` (rad): the blend starts at anchor - (program - dtheta). False when any joint of it is
  /// beyond the tolerance (distance() tells each joint's, rad); the stream is then unchanged. Never
  /// allocates.
  bool begin(const JointVector& anchor, const JointVector& dtheta) noexcept;
  /// The program at the stream's time and its velocity (rad, rad/s), the blend now and its velocity.
  void sample(JointVector& program, JointVector& program_velocity, JointVector& blend,
              JointVector& blend_velocity) const noexcept;
  /// One controller cycle consumed (an answer went out): the program and the blend move on by period_s
  /// (during a stop ramp, the program by the ramp's share of it).
  void consumed(double period_s) noexcept;
  /// A planned stop: the program slows to a standstill over `ramp_s` (> 0) of consumed cycles. Once
  /// begun, later calls change nothing.
  void begin_stop(double ramp_s) noexcept;
  [[nodiscard]] bool stopping() const { return stop_ramp_s_ > 0.0; }
  /// The stop ramp has brought the program to rest (or the program had ended).
  [[nodiscard]] bool at_standstill() const {
    return finished() || (stopping() && stop_elapsed_s_ >= stop_ramp_s_ - 1e-12);
  }
  /// The program's speed factor now: 1 while it runs, falling to 0 over a stop ramp.
  [[nodiscard]] double speed_factor() const;

  [[nodiscard]] bool started() const { return started_; }
  [[nodiscard]] bool finished() const { return program_t_s_ >= trajectory_->end_time_s(); }
  /// True while a blend is still being taken out.
  [[nodiscard]] bool blending() const { return blend_t_s_ < config_.ramp_in_s && offset_.cwiseAbs().maxCoeff() > 0.0; }
  /// Time along the program (its own time axis).
  [[nodiscard]] double program_time_s() const { return program_t_s_; }
  [[nodiscard]] const JointVector& distance() const { return distance_; }
  [[nodiscard]] const JointTrajectory& trajectory() const { return *trajectory_; }
  [[nodiscard]] const JointStreamConfig& config() const { return config_; }

 private:
  std::shared_ptr<const JointTrajectory> trajectory_;
  JointStreamConfig config_;
  bool started_ = false;
  double program_t_s_ = 0.0;
  double blend_t_s_ = 0.0;  // time since the current blend began (cycles consumed)
  // Cycles consumed, counted: the times are start + n x period, so thousands of cycles add no
  // rounding (a sum of 0.1 s steps would miss the program's end by an ulp).
  std::uint64_t cycles_ = 0, blend_cycles_ = 0;
  double stop_ramp_s_ = 0.0;     // > 0: a stop ramp of this length runs
  double stop_elapsed_s_ = 0.0;  // consumed time since it began
  JointVector offset_;           // the blend's offset at its start
  JointVector distance_;
  mutable JointVector scratch_, scratch_velocity_;
};

}  // namespace deflex
