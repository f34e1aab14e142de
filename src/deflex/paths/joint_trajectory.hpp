// A timed joint trajectory: the nominal program a streaming controller link holds and sends
// (deflex online --program), or the program a simulated controller runs. Read from and written to
// CSV `t_s,q1_deg,...,qN_deg` (times increasing), checked against the robot before anything moves:
// times strictly increasing, every point inside the joint limits, and no joint faster than its speed
// limit anywhere along the interpolation. Sampled at any time by a piecewise cubic (C1, passing
// through every point), starting and ending at rest; before the first time it holds the first
// point, after the last it holds the last (a clean end).
#pragma once

#include <string>
#include <vector>

#include "deflex/model/robot_model.hpp"

namespace deflex {

/// Thread safety: immutable once built: sample() and every const call from any number of threads
/// (sessions and simulated controllers share one as std::shared_ptr<const JointTrajectory>).
class JointTrajectory {
 public:
  JointTrajectory() = default;
  /// Times (s) and joints (rad), one entry a point, at least two points. Throws InputError naming
  /// `source`, the point ("point 3", or "line 5" when the trajectory came from a file) and the joint
  /// for non-increasing or non-finite times, joints beyond the limits, or a speed above a joint's
  /// speed limit (when the robot has them).
  JointTrajectory(std::vector<double> t_s, std::vector<JointVector> q, const RobotModel& model,
                  std::string source = "<memory>", std::vector<int> lines = {});

  /// Reads `t_s,q1_deg,...,qN_deg` (N the robot's joints; other columns are an error). Throws
  /// DataError for a malformed file and InputError for a trajectory the robot cannot follow, both
  /// naming the file and line.
  static JointTrajectory read_csv(const std::string& path, const RobotModel& model);
  /// The CSV form (degrees, times as given), with `comment` as a '#' line first when not empty.
  [[nodiscard]] std::string csv_text(const std::string& comment = "") const;
  /// csv_text() to a file of its own (output_file.hpp). Throws InputError or OutputError naming it.
  void write_csv(const std::string& path, const std::string& comment = "") const;

  /// Joints (rad) and, if asked, joint velocities (rad/s) at time t_s. Never allocates or throws.
  void sample(double t_s, JointVector& q, JointVector* qd = nullptr) const noexcept;

  [[nodiscard]] std::size_t size() const { return t_.size(); }
  [[nodiscard]] int dof() const { return q_.empty() ? 0 : static_cast<int>(q_.front().size()); }
  [[nodiscard]] double start_time_s() const { return t_.front(); }
  [[nodiscard]] double end_time_s() const { return t_.back(); }
  [[nodiscard]] double duration_s() const { return t_.back() - t_.front(); }
  [[nodiscard]] const std::vector<double>& times_s() const { return t_; }
  [[nodiscard]] const std::vector<JointVector>& points() const { return q_; }
  [[nodiscard]] const std::string& source() const { return source_; }
  /// Largest joint speed along the interpolation, rad/s per joint.
  [[nodiscard]] const JointVector& peak_speed() const { return peak_speed_; }

 private:
  std::vector<double> t_;
  std::vector<JointVector> q_;
  std::vector<JointVector> m_;  // tangents (rad/s) at the points
  JointVector peak_speed_;
  std::string source_;
};

/// Times a sampled TCP path for a constant TCP speed (m/s): t_0 = hold_start_s, and each point
/// |p_i - p_{i-1}| / speed after the previous one (at least 1 ms, for points at the same position).
/// `poses` (base_T_tcp) and `q` (their joints) are the same length. Throws InputError on a bad speed,
/// mismatched lengths or a pose whose position is not finite (naming it, 0-based), and as the
/// constructor does when the result breaks a joint limit.
[[nodiscard]] JointTrajectory trajectory_at_tcp_speed(const std::vector<Pose>& poses, const std::vector<JointVector>& q,
                                                      double speed_m_s, const RobotModel& model,
                                                      double hold_start_s = 0.0);

}  // namespace deflex
