// Analytic inverse kinematics of ortho-parallel 6R arms (opw_geometry.hpp): every branch of one
// pose in closed form, each checked by the canonical forward kinematics, mapped to the model's
// joints with the 2*pi turn nearest a seed inside the joint limits, with its ABB and KUKA
// configuration. Fixed-size results, no heap allocation, no exceptions: a hot-path call.
#pragma once

#include <array>
#include <cstdint>

#include "deflex/model/inverse_kinematics.hpp"

namespace deflex {

/// One branch before the choice of turns: canonical angles and what the branch is. Left
/// uninitialised on purpose (opw_branches() fills every field of the branches it counts), so a
/// result on the stack costs nothing to create.
struct OpwBranch {
  std::array<double, 6> theta;
  double wrist_x_a1;       ///< wrist centre's x in the A1 frame, m (negative: behind axis 1)
  double lower_arm_cross;  ///< (upper arm direction x (wrist centre - axis 2)) . y, A1 frame
  std::uint8_t branch;     ///< bit 2 shoulder back, bit 1 second elbow, bit 0 wrist flipped
  Singularity singularity;
  double position_error_m;   ///< canonical FK against the target, wrist centre
  double orientation_error;  ///< Frobenius norm of the rotation difference (~ rad)
  std::array<double, 6> q;   ///< the model's joints at the chosen turns (set only with OpwJointFit)
};

/// Up to eight branches of one pose, in the canonical frame.
struct OpwBranches {
  std::array<OpwBranch, 8> branch;
  int count = 0;
  bool reachable = false;
};

/// How opw_branches() turns canonical angles into the model's joints: each joint at the 2*pi turn
/// nearest `reference` inside [lower, upper] (rad); a branch where some joint has none is dropped.
struct OpwJointFit {
  const JointVector& lower;
  const JointVector& upper;
  const JointVector* reference;  ///< the seed; zero when null
};

/// The arms (a shoulder and an elbow each) opw_branches() and opw_solutions() solve: bit
/// 2 * shoulder + elbow (shoulder 1: back, elbow 1: the second elbow, as OpwBranch::branch), all four
/// by default. A caller that knows which arm it wants (path IK, which keeps one configuration) asks
/// for that one and pays for no other.
inline constexpr unsigned kOpwAllArms = 0xFU;

/// Solves the canonical pose `opw_T_end` (the target already moved into the canonical frame).
/// `theta4_when_singular` is the theta4 kept when the wrist is exactly singular (only theta4 +
/// theta6 is fixed there). Branches that fail the FK check (1e-8 m, 1e-8) are dropped. With `fit`,
/// each branch also gets its joint values (OpwBranch::q), and those where some joint has no turn
/// inside its limits are dropped, joint by joint as the branch is built, so the work for the rest
/// of it is saved. `reachable` tells an unreachable pose from one whose branches all left the limits
/// (of the shoulders `arms` asks for). Only the arms in `arms` are solved.
void opw_branches(const OpwGeometry& g, const Pose& opw_T_end, double theta4_when_singular,
                  double near_singular_threshold, const OpwJointFit* fit, OpwBranches& out,
                  unsigned arms = kOpwAllArms);

/// One solution in the model's joints.
struct OpwSolution {
  Eigen::Matrix<double, 6, 1> q = Eigen::Matrix<double, 6, 1>::Zero();  ///< rad, inside the joint limits
  ArmConfiguration configuration;                                       ///< ABB confdata
  KukaConfiguration kuka;                                               ///< KUKA Status and Turn
  std::uint8_t branch = 0;                                              ///< as OpwBranch::branch
  Singularity singularity = Singularity::kNone;
  double position_error_m = 0.0;
  double orientation_error = 0.0;
};

struct OpwSolutions {
  std::array<OpwSolution, 8> solution;
  int count = 0;
  /// kOk, kNearSingular (at least one solution near a singularity), kUnreachable,
  /// kOutsideJointLimits (reachable, no branch fits the limits), kInvalidInput (no OPW geometry,
  /// seed of the wrong size).
  IkStatus status = IkStatus::kInvalidInput;
};

/// Every solution of the TCP pose `base_T_tcp` (robot base frame): one per branch, each joint at
/// its 2*pi turn nearest `seed` (or zero without one) that fits the joint limits, FK-checked, with
/// its ABB and KUKA configuration. Allocation-free. With `arms`, only those arms' branches (status
/// kUnreachable then says that none of their shoulders reaches the pose).
void opw_solutions(const RobotModel& model, const Pose& base_T_tcp, const JointVector* seed, OpwSolutions& out,
                   double near_singular_threshold = 1e-2, unsigned arms = kOpwAllArms);

/// ABB and KUKA configuration of joint values of an OPW arm, from the canonical geometry (no FK).
void opw_configuration(const OpwGeometry& g, const JointVector& q, ArmConfiguration& abb, KukaConfiguration& kuka);

}  // namespace deflex
