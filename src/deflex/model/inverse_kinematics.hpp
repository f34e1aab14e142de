// Inverse kinematics of the TCP. Analytic for every ortho-parallel 6R arm with a spherical wrist
// (the OPW family: ABB, KUKA, FANUC, Staubli, Yaskawa industrial arms, from a DH table or a URDF;
// opw_geometry.hpp): every solution, chosen by ABB's confdata or KUKA's Status/Turn and a seed.
// Damped least squares for other arms. Singular poses are reported (status and kind), never
// divided through. The allocation-free all-solutions call for hot paths is in opw_ik.hpp.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/model/arm_configuration.hpp"
#include "deflex/model/kinematics.hpp"

namespace deflex {

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
  /// Wanted KUKA Status and Turn (analytic solver only): the status has to match, and each joint
  /// takes the turn whose sign the Turn bit gives.
  std::optional<KukaConfiguration> kuka_configuration;
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
  KukaConfiguration kuka;  ///< Status and Turn of q
  Singularity singularity = Singularity::kNone;
  double position_error_m = 0.0;
  double orientation_error_rad = 0.0;
  bool analytic = false;
  std::string message;  ///< why it failed, or which singularity is near
  [[nodiscard]] bool ok() const { return static_cast<int>(status) >= 0; }
};

/// True when the analytic solver applies to this model (model.opw() is set; see the file comment).
[[nodiscard]] bool has_analytic_ik(const RobotModel& model);

/// The configuration (confdata) of a joint vector.
[[nodiscard]] ArmConfiguration arm_configuration(const RobotModel& model, Workspace& ws, const JointVector& q);

/// KUKA Status and Turn of a joint vector (the model's joint values taken as A1..A6). For arms
/// outside the OPW family, status bit 1 is the geometric equivalent: the wrist centre is not behind
/// the lower arm.
[[nodiscard]] KukaConfiguration kuka_configuration(const RobotModel& model, Workspace& ws, const JointVector& q);

/// TCP pose (base frame) to joints.
[[nodiscard]] IkResult inverse_kinematics(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                          const IkRequest& request = {});

/// Every analytic solution inside the joint limits (all 2*pi turns of each joint), checked by FK; with
/// a seed, the nearest it first (the largest joint difference), so [0] has each joint at the turn
/// nearest the seed. Empty for arms without an analytic solver. Throws InputError for a seed that is
/// not dof finite values. (Allocates; opw_solutions() is the hot-path form.)
[[nodiscard]] std::vector<IkResult> all_ik_solutions(const RobotModel& model, Workspace& ws, const Pose& base_T_tcp,
                                                     const IkRequest& request = {});

/// Smallest singular value of the 6xn TCP Jacobian at q (0 at a singularity; units mixed m/rad).
[[nodiscard]] double jacobian_min_singular_value(const RobotModel& model, Workspace& ws, const JointVector& q);

}  // namespace deflex
