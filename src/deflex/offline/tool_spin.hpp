// The spindle's free angle along a toolpath. A milling spindle is symmetric about its axis, so a
// 6-axis arm following a toolpath has one free rotation at every point: the spin of the TCP frame
// about the tool axis. deflex either keeps it fixed or chooses it for stiffness: along the path, the
// angles that minimise the predicted deflection of the tool tip under the predicted wrench, subject
// to the arm's reach in the path's one arm configuration, a margin from the joint limits, a floor on
// the distance from singularities, and a bounded rate of change along the path.
//
// Conventions (docs/machining.md, "From CAM to a compensated program"): the TCP sits at the tool tip,
// its z axis is -tool_axis (out of the spindle along the tool, towards the tip); its x axis is the
// spin reference turned by the spin about TCP z (right hand). The reference is the workpiece's x
// projected on the plane normal to the tool axis at the first point, carried along the path by the
// smallest rotation that follows the tool axis (a 3-axis path's reference is the workpiece's x
// throughout).
//
// The choice is a dynamic programme (Viterbi) over a grid of candidate angles at stages spaced
// step / rate apart along the path, so that one grid step between stages is the rate bound; between
// stages the angle moves linearly with the path length. Each stage solves the IK, the joint limits,
// the singularity floor and the compliance J K^-1 J^T of every candidate once; every cutting point
// between two stages is costed against each candidate with the compliance interpolated between them,
// so the figure minimised is the sum over the cutting points of the first-order deflection |C W|.
// Decisions are made a fixed number of stages behind the newest (fixed-lag decoding), so a path of
// any length streams in bounded memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "deflex/model/inverse_kinematics.hpp"

namespace deflex {

/// TCP orientation for a tool axis (unit, tip into the spindle), a spin reference (unit, normal to
/// the axis) and a spin angle: columns x, y, z of base_R_tcp in the frame the vectors are given in.
[[nodiscard]] Matrix3 tcp_rotation(const Vector3& tool_axis, const Vector3& reference_x, double spin_rad);

/// The spin reference along a path (see the file comment).
/// Thread safety: one thread at a time (next() moves it on).
class SpinReference {
 public:
  /// The reference at the next point, whose tool axis is `tool_axis` (unit).
  const Vector3& next(const Vector3& tool_axis);

 private:
  Vector3 axis_ = Vector3::Zero();
  Vector3 x_ = Vector3::UnitX();
  bool started_ = false;
};

struct ToolSpinOptions {
  bool optimize = true;
  double fixed_rad = 0.0;  ///< the spin when not optimised
  /// The candidate angles are every grid_step_rad (a divisor of 360 deg, 2..60 deg).
  double grid_step_rad = 10.0 * kPi / 180.0;
  /// The largest change of the spin per metre of path, rad/m (default 1 deg per mm).
  double max_rate_rad_per_m = 1000.0 * kPi / 180.0;
  /// For the rate, a move longer than this counts this long (a long rapid turns the spin at most
  /// max_rate * this between its two ends), m.
  double move_counted_max_m = 15e-3;
  /// Candidates whose joints come nearer than this to a limit are out, rad.
  double joint_limit_margin_rad = 5.0 * kPi / 180.0;
  /// Candidates nearer a singularity than this are out: |sin q5| for the wrist, |sin| of the elbow
  /// angle, and the wrist centre's distance from axis 1 (m) for the shoulder (the analytic IK's
  /// measures, inverse_kinematics.hpp).
  double singularity_floor = 0.1;
  /// Stages between the newest and the one decided (fixed-lag decoding); memory grows with it.
  std::size_t lag_stages = 50;
  /// Points held before a stage is forced (the spin then holds still across it).
  std::size_t max_buffered_points = 100000;

  [[nodiscard]] double stage_spacing_m() const { return grid_step_rad / max_rate_rad_per_m; }
};

/// "optimize", "optimize:step_deg=10,rate_deg_per_mm=1,limit_margin_deg=5,singularity_floor=0.1,
/// lag_stages=50" (every key optional) or "fixed:DEG". Throws InputError quoting the spec and naming the
/// key: an unknown kind or key, a step that does not divide 360 or is outside 2..60 deg, a rate outside
/// 0.01..100 deg/mm, a margin outside 0..30 deg, a floor outside 0..0.5, a lag outside 1..1000, an
/// angle outside +-360 deg.
[[nodiscard]] ToolSpinOptions parse_tool_spin_spec(const std::string& spec);

/// One line for humans.
[[nodiscard]] std::string describe_tool_spin(const ToolSpinOptions& options);

/// A toolpath point as the spin's choice needs it, in the robot's base frame.
struct SpinPoint {
  Vector3 tip_m = Vector3::Zero();
  Vector3 tool_axis = Vector3::UnitZ();    ///< unit, tip into the spindle
  Vector3 reference_x = Vector3::UnitX();  ///< the spin reference (SpinReference), base frame
  Wrench wrench = Wrench::Zero();          ///< on the robot, moment about the TCP (the tip)
  bool cutting = false;                    ///< counted in the figure minimised
  double move_m = 0.0;                     ///< length of the move into the point
  std::size_t line = 0;                    ///< source line, for messages
};

/// What the choice did.
struct ToolSpinStats {
  std::size_t stages = 0;
  std::size_t candidate_solves = 0;
  std::size_t forced_stages = 0;  ///< stages forced by max_buffered_points
  /// Fixed spin: stages where the angle breaks the margins or the singularity floor (the optimiser
  /// would refuse it there), and the first such line.
  std::size_t margin_violations = 0;
  std::size_t first_margin_violation_line = 0;
};

/// The spin of every point of a path, streamed: push() the points in order, pop() the decided spins
/// in the same order, finish() after the last point.
/// Thread safety: one thread at a time; planners on different threads may share the model.
class ToolSpinPlanner {
 public:
  /// `first` chooses the path's arm configuration (its configuration, or the solution nearest its
  /// seed or zero at the first candidate that reaches the first point). Throws InputError for options
  /// out of range.
  ToolSpinPlanner(const RobotModel& model, const ToolSpinOptions& options, const IkRequest& first);
  ToolSpinPlanner(RobotModel&& model, const ToolSpinOptions& options, const IkRequest& first) = delete;
  ~ToolSpinPlanner();
  ToolSpinPlanner(const ToolSpinPlanner&) = delete;
  ToolSpinPlanner& operator=(const ToolSpinPlanner&) = delete;

  /// The next point. Throws InputError "line N: ..." when no candidate angle reaches a stage (the
  /// arm cannot reach the point at any spindle angle), or none does within the rate bound from the
  /// angles before it.
  void push(const SpinPoint& point);
  /// Every point is pushed: the rest is decided.
  void finish();
  /// The spin (rad, in -pi..pi) of the oldest point not popped yet, when it is decided.
  bool pop(double& spin_rad);

  /// The arm configuration and the first point's joints at its spin (valid once a point is decided):
  /// the IK request that makes the path's IK follow the planner.
  [[nodiscard]] IkRequest path_request() const;
  [[nodiscard]] const ToolSpinStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace deflex
