// Inverse kinematics of the TCP. Analytic for 6R arms in standard DH with joints 2 and 3 parallel
// and a spherical wrist (the IRB6700 and most industrial arms): every solution, chosen by an
// ABB-style configuration (confdata cf1, cf4, cf6, cfx). Damped least squares for other arms.
// Singular poses are reported (status and kind), never divided through.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/model/kinematics.hpp"

namespace deflex {

/// ABB's confdata. cf1, cf4, cf6: quadrant of joints 1, 4, 6 (floor(q / 90 deg): 0 for [0, 90),
/// -1 for [-90, 0), ...). cfx (0..7) = 4*b1 + 2*b2 + b3 with
///   b1: wrist centre behind axis 1 (along the x axis of joint 1's moving frame),
///   b2: wrist centre behind the lower arm (reached from the axis-2-to-axis-3 direction by a
///       negative rotation about joint 2's axis),
///   b3: joint 5 negative.
struct ArmConfiguration {
  int cf1 = 0;
  int cf4 = 0;
  int cf6 = 0;
  int cfx = 0;
  bool operator==(const ArmConfiguration&) const = default;
};

/// KDL's sign convention: positive is usable but degraded, negative is failure.
enum class IkStatus : int {
  kOk = 0,
  kNearSingular = 1,               ///< solved, but close to a singularity (see IkResult::singularity)
  kUnreachable = -1,               ///< outside the workspace
  kOutsideJointLimits = -2,        ///< reachable, but every solution violates a joint limit
  kConfigurationUnavailable = -3,  ///< solutions exist, none with the requested configuration
  kNotConverged = -4,              ///< numerical solver did not reach the tolerance
  kInvalidInput = -5,              ///< non-finite target, not a rotation, wrong seed size
};

enum class Singularity { kNone, kWrist, kElbow, kShoulder, kUnknown };

[[nodiscard]] const char* to_string(IkStatus s);
[[nodiscard]] const char* to_string(Singularity s);

struct IkRequest {
  /// Wanted configuration. cfx always has to match; cf1/cf4/cf6 too when match_quadrants.
  std::optional<ArmConfiguration> configuration;
  bool match_quadrants = true;
  /// Preferred solution: among those allowed, the closest to the seed (max joint difference).
  /// Also the start of the numerical solver. Typical use: the previous point of a path.
  std::optional<JointVector> seed;
  /// Below this, |sin q5| (wrist), |sin elbow angle| (elbow) or the wrist centre's distance from
  /// axis 1 in m (shoulder) counts as near singular.
  double near_singular_threshold = 1e-2;
  double tolerance = 1e-10;  ///< numerical solver: m and rad
};

struct IkResult {
  IkStatus status = IkStatus::kInvalidInput;
  JointVector q;  ///< rad; valid when status >= 0
  ArmConfiguration configuration;
  Singularity singularity = Singularity::kNone;
  double position_error_m = 0.0;
  double orientation_error_rad = 0.0;
  bool analytic = false;
  std::string message;  ///< why it failed, or which singularity is near
  [[nodiscard]] bool ok() const { return static_cast<int>(status) >= 0; }
};

/// True when the analytic solver applies to this model (see the file comment).
[[nodiscard]] bool has_analytic_ik(const RobotModel& model);

/// The configuration (confdata) of a joint vector.
[[nodiscard]] ArmConfiguration arm_configuration(const RobotModel& model, Workspace& ws, const JointVector& q);

/// TCP pose (base frame) to joints.
[[nodiscard]] IkResult inverse_kinematics(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                          const IkRequest& request = {});

/// Every analytic solution inside the joint limits (all 2*pi turns of each joint), checked by FK.
/// Empty for arms without an analytic solver.
[[nodiscard]] std::vector<IkResult> all_ik_solutions(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                                     const IkRequest& request = {});

/// Smallest singular value of the 6xn TCP Jacobian at q (0 at a singularity; units mixed m/rad).
[[nodiscard]] double jacobian_min_singular_value(const RobotModel& model, Workspace& ws, const JointVector& q);

}  // namespace deflex
