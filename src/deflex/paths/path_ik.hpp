// Inverse kinematics along a sampled TCP path with one arm configuration kept, so the robot does not
// swing between solutions in the middle of a path.
#pragma once

#include <vector>

#include "deflex/model/inverse_kinematics.hpp"

namespace deflex {

/// Joint values along a path, rad, one entry a pose, and the arm configuration (confdata) chosen at
/// the first point. cfx (the branch: shoulder, elbow, wrist flip) is the same at every point; the
/// quadrants cf1, cf4, cf6 may change along the way when a joint crosses a multiple of 90 degrees,
/// as they do on a real controller.
struct JointPath {
  std::vector<JointVector> q;
  ArmConfiguration configuration;
};

struct PathIkOptions {
  /// Largest change of any joint between neighbouring points. A larger step means the nearest
  /// solution lies on the other side of a singularity or a joint wrapped: the path is not
  /// followable with the chosen configuration, or it is sampled too coarsely. 30 deg by default
  /// (a circle of 81 points moves the IRB6700's joints by about 1 deg a point). Must be > 0 (infinity:
  /// no bound); the solver refuses anything else, NaN included, when it is made.
  double max_joint_step_rad = deg_to_rad(30.0);
  /// Near-singular poses stop the path (IK there is ill-conditioned and the compensation would
  /// move joints by large amounts); set true to accept them.
  bool allow_near_singular = false;
};

/// The opw_solutions() arm mask (opw_ik.hpp) of the arm whose branches have configuration `cfx` away
/// from the shoulder and elbow singularities: one shoulder and one elbow.
[[nodiscard]] unsigned opw_arm_of_configuration(const OpwGeometry& g, int cfx);

/// Solves every pose of `poses` (base_T_tcp). The first point uses `first` as given (its
/// configuration and seed pick the solution); every later point keeps the first point's cfx and is
/// the solution closest to the previous point. Throws InputError "path point I: REASON" (I 0-based)
/// when a point is unreachable, near a singularity, outside the joint limits, has no solution with
/// the configuration, or jumps by more than max_joint_step_rad; and when `poses` is empty.
[[nodiscard]] JointPath solve_path_ik(const RobotModel& model, const std::vector<Pose>& poses, const IkRequest& first,
                                      const PathIkOptions& options);
[[nodiscard]] JointPath solve_path_ik(const RobotModel& model, const std::vector<Pose>& poses, const IkRequest& first);

/// The same, a pose at a time, for paths too long to hold (deflex offline streams them): next()
/// gives exactly what solve_path_ik gives for that point, and throws the same InputError. After the
/// first point of an ortho-parallel arm, next() solves only the arm (shoulder and elbow) the path's
/// configuration allows, which no other arm shares away from the shoulder and elbow singularities;
/// near them, and whenever that arm gives no usable answer, it solves every branch as the first point does.
/// Thread safety: one thread at a time (its own Workspace); solvers on different threads may share
/// the model.
class PathIkSolver {
 public:
  /// Throws InputError when options.max_joint_step_rad is not > 0.
  PathIkSolver(const RobotModel& model, const IkRequest& first, const PathIkOptions& options = {});
  /// The solver keeps a reference to the model: a temporary would dangle, so it does not compile.
  PathIkSolver(RobotModel&& model, const IkRequest& first, const PathIkOptions& options = {}) = delete;
  /// Joint values of the next path point (its 0-based index is points() before the call).
  const JointVector& next(const Pose& base_T_tcp);
  [[nodiscard]] std::size_t points() const { return index_; }
  /// The first point's arm configuration (valid once a point was solved).
  [[nodiscard]] const ArmConfiguration& configuration() const { return configuration_; }

 private:
  /// The next point from the one arm `arm_` (an opw_solutions() arm mask; 0: not applicable); false
  /// when that does not settle it (the full solve then decides, and reports any failure).
  bool next_on_path_arm(const Pose& base_T_tcp);

  const RobotModel& model_;
  PathIkOptions options_;
  Workspace ws_;
  IkRequest request_;
  ArmConfiguration configuration_;
  JointVector q_;
  std::size_t index_ = 0;
  unsigned arm_ = 0;
};

}  // namespace deflex
