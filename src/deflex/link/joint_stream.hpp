// The nominal a streaming link holds (ABB EGM position guidance, ROS-Industrial simple message): the
// program deflex streams, on a clock that starts with the controller's first message. The program
// never comes from the controller's echo: in position guidance the controller reports deflex's own
// last command as "planned", and a reply built on it would integrate its own correction.
//   - start: the arm must be within a tolerance of the program's start, or the link refuses;
//   - ramp-in: the small offset between where the arm is and the program's start is blended out
//     (smoothstep) over the ramp time, so the first command equals where the arm is;
//   - pauses: a silence of the controller stops the program clock (the arm held its target); when
//     messages come again the arm must again be within the tolerance, and the blend starts afresh;
//   - end: the last point is held.
#pragma once

#include <memory>

#include "deflex/paths/joint_trajectory.hpp"

namespace deflex {

struct JointStreamConfig {
  double ramp_in_s = 1.0;                        ///< s, blend from the arm's start to the program
  double start_tolerance_rad = kPi / 180.0;      ///< the arm must be this close to the program (1 deg)
  double pause_after_s = 0.5;                    ///< a silence this long stops the program clock
  /// Throws InputError on a negative or non-finite value.
  void validate() const;
};

class JointStream {
 public:
  /// `trajectory` is shared (a long program is not copied). Throws InputError on a bad config.
  JointStream(std::shared_ptr<const JointTrajectory> trajectory, const JointStreamConfig& config);

  /// A session starts (first message, or the first after a pause) with the arm at q_feedback. False
  /// when any joint is farther than the tolerance from where the program is; distance() tells each
  /// joint's distance (rad). Never allocates.
  bool begin(double t_s, const JointVector& q_feedback) noexcept;
  /// True when the controller was silent for pause_after_s before t_s (a new session must begin).
  [[nodiscard]] bool paused_at(double t_s) const noexcept { return started_ && t_s - last_t_s_ > config_.pause_after_s; }
  /// Advances the program clock to t_s and gives the nominal (rad) and its velocity (rad/s).
  void advance(double t_s, JointVector& q, JointVector& qd) noexcept;

  [[nodiscard]] bool started() const { return started_; }
  [[nodiscard]] bool finished() const { return program_t_s_ >= trajectory_->end_time_s(); }
  /// Time along the program (its own time axis).
  [[nodiscard]] double program_time_s() const { return program_t_s_; }
  [[nodiscard]] const JointVector& distance() const { return distance_; }
  [[nodiscard]] const JointTrajectory& trajectory() const { return *trajectory_; }

 private:
  std::shared_ptr<const JointTrajectory> trajectory_;
  JointStreamConfig config_;
  bool started_ = false;
  double last_t_s_ = 0.0;
  double program_t_s_ = 0.0;
  double blend_start_s_ = 0.0;  // program time the current blend began
  JointVector offset_;          // arm minus program at the session's start
  JointVector distance_;
  JointVector scratch_;
};

}  // namespace deflex
