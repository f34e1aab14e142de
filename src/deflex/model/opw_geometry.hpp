// The geometry of an ortho-parallel 6R arm with a spherical wrist (the OPW family of Brandstoetter,
// Angerer and Hofbaur, "An analytical solution of the inverse kinematics problem of industrial
// serial manipulators with an ortho-parallel basis and a spherical wrist", Austrian Robotics
// Workshop 2014): seven lengths plus a sign and an offset per joint, derived from any chain (DH
// table or URDF) at load time, so one analytic solver serves ABB, KUKA, FANUC, Staubli and Yaskawa
// arms whatever their zero pose and joint directions.
//
// The canonical arm (lengths in m): axis 1 is z; at all canonical angles zero the arm stands
// straight up. Axis 2 is parallel to y through (a1, *, c1); the upper arm of length c2 runs along z
// to axis 3 (parallel to axis 2); from there the wrist centre lies a2 along x and c3 along z, and b
// along y from the arm's plane; axis 4 runs along z through the wrist centre; axes 4, 5, 6 are
// z, y, z and meet at the wrist centre; the end frame sits c4 along axis 6 from it. Canonical joint
// angles theta relate to the model's joint values q by theta_i = sign_i * q_i + offset_i.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "deflex/model/types.hpp"

namespace deflex {

class RobotModel;

struct OpwGeometry {
  double a1 = 0.0, a2 = 0.0, b = 0.0, c1 = 0.0, c2 = 0.0, c3 = 0.0, c4 = 0.0;  ///< m
  std::array<double, 6> sign{1, 1, 1, 1, 1, 1};                                ///< theta_i = sign_i * q_i + offset_i
  std::array<double, 6> offset{0, 0, 0, 0, 0, 0};                              ///< rad

  Pose chain_T_opw = Pose::Identity();   ///< the canonical base frame in the chain's frame
  Pose end_T_flange = Pose::Identity();  ///< canonical end frame to the model's flange (rigid on link 6)
  /// For the solver, with the model's base and tool folded in:
  /// canonical end frame = opw_T_base * base_T_tcp * tcp_T_end.
  Pose opw_T_base = Pose::Identity();
  Pose tcp_T_end = Pose::Identity();
  /// Both rotations above are the identity, as fold_step() classifies it (a tool that only moves the
  /// TCP, a base frame without a turn): the solver's frame change is then additions only.
  bool frames_unrotated = false;

  /// sqrt(a2^2 + c3^2) and the angle of the forearm vector (a2, c3) from the z axis.
  double k = 0.0;
  double inv_2_c2_k = 0.0;  ///< 1 / (2 c2 k), for the law of cosines at the elbow
  double psi = 0.0, psi_cos = 1.0, psi_sin = 0.0;
  /// The q3 at which the wrist centre lies on the line of the upper arm (KUKA's phi), rad.
  double q3_stretched = 0.0;

  /// Canonical angles of joint values (rad).
  [[nodiscard]] double theta(int i, double q) const {
    return sign[static_cast<std::size_t>(i)] * q + offset[static_cast<std::size_t>(i)];
  }
  [[nodiscard]] double joint(int i, double theta) const {
    return sign[static_cast<std::size_t>(i)] * (theta - offset[static_cast<std::size_t>(i)]);
  }
};

/// The model's OPW geometry, or none with the reason in `why_not` (not six joints, axes 2 and 3 not
/// parallel, no spherical wrist, ...). Checked: the canonical arm must reproduce the model's flange
/// pose at several configurations to 1e-9 m and rad, or the model gets none. Called once by the
/// RobotModel constructor (its base and tool frames are folded into opw_T_base and tcp_T_end).
[[nodiscard]] std::optional<OpwGeometry> derive_opw_geometry(const RobotModel& model, std::string& why_not);

/// Canonical end frame for canonical angles theta (rad): the closed-form forward kinematics.
[[nodiscard]] Pose opw_forward(const OpwGeometry& g, const std::array<double, 6>& theta);

/// The wrist centre in the A1 frame (x forward of axis 1, z along it), m, for canonical theta2 and
/// theta2 + theta3.
[[nodiscard]] inline Vector3 opw_wrist_centre_a1(const OpwGeometry& g, double theta2, double phi) {
  const double s2 = std::sin(theta2), c2 = std::cos(theta2), sp = std::sin(phi), cp = std::cos(phi);
  return {g.a1 + g.c2 * s2 + g.a2 * cp + g.c3 * sp, g.b, g.c1 + g.c2 * c2 - g.a2 * sp + g.c3 * cp};
}

}  // namespace deflex
