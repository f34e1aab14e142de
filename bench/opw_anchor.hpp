// The benchmark's anchor for deflex's analytic IK: the closed form of Brandstoetter, Angerer and
// Hofbaur, "An analytical solution of the inverse kinematics problem of industrial serial
// manipulators with an ortho-parallel basis and a spherical wrist" (Austrian Robotics Workshop
// 2014), written here from the paper's equations, as bare as the paper has it: eight branches
// with std::atan2, std::acos and std::sqrt, then the joint signs and offsets; no joint limits, no
// 2*pi turns, no check by forward kinematics, no configuration. A branch the arm cannot reach comes
// out as NaN, as in the paper. Benchmark code only: deflex itself never calls it.
#pragma once

#include <array>
#include <cmath>

#include "deflex/model/opw_geometry.hpp"

namespace deflex::bench {

using OpwAnchorSolutions = std::array<std::array<double, 6>, 8>;

/// Every branch of the canonical end pose `opw_T_end` (the target already in the canonical frame),
/// as the model's joint values q_i = sign_i * (theta_i - offset_i), rad.
inline void opw_anchor_ik(const OpwGeometry& g, const Pose& opw_T_end, OpwAnchorSolutions& q) {
  const Matrix3& e = opw_T_end.linear();
  // Wrist centre C = u - c4 * e_z.
  const double cx = opw_T_end.translation().x() - g.c4 * e(0, 2);
  const double cy = opw_T_end.translation().y() - g.c4 * e(1, 2);
  const double cz = opw_T_end.translation().z() - g.c4 * e(2, 2);
  const double nx1 = std::sqrt(cx * cx + cy * cy - g.b * g.b) - g.a1;
  const double dz = cz - g.c1;
  const double s1_2 = nx1 * nx1 + dz * dz;
  const double s2_2 = (nx1 + 2.0 * g.a1) * (nx1 + 2.0 * g.a1) + dz * dz;
  const double k_2 = g.a2 * g.a2 + g.c3 * g.c3;
  const double s1 = std::sqrt(s1_2);
  const double s2 = std::sqrt(s2_2);

  // Joint 1: two shoulders.
  const double base = std::atan2(cy, cx);
  const double side = std::atan2(g.b, nx1 + g.a1);
  const double t1_i = base - side;
  const double t1_ii = base + side - kPi;

  // Joints 2 and 3: two elbows per shoulder, from the law of cosines.
  const double a_s1 = std::acos((s1_2 + g.c2 * g.c2 - k_2) / (2.0 * s1 * g.c2));
  const double a_s2 = std::acos((s2_2 + g.c2 * g.c2 - k_2) / (2.0 * s2 * g.c2));
  const double to_c_front = std::atan2(nx1, dz);
  const double to_c_back = std::atan2(nx1 + 2.0 * g.a1, dz);
  const std::array<double, 4> t2 = {-a_s1 + to_c_front, a_s1 + to_c_front, -a_s2 - to_c_back, a_s2 - to_c_back};
  const double psi = std::atan2(g.a2, g.c3);
  const double b_s1 = std::acos((s1_2 - g.c2 * g.c2 - k_2) / (2.0 * g.c2 * std::sqrt(k_2)));
  const double b_s2 = std::acos((s2_2 - g.c2 * g.c2 - k_2) / (2.0 * g.c2 * std::sqrt(k_2)));
  const std::array<double, 4> t3 = {b_s1 - psi, -b_s1 - psi, b_s2 - psi, -b_s2 - psi};
  const std::array<double, 4> t1 = {t1_i, t1_i, t1_ii, t1_ii};

  // Joints 4 to 6 of each arm solution p, and the flipped wrist q = p + 4; theta1's sine and
  // cosine once a shoulder.
  const std::array<double, 2> s1s = {std::sin(t1_i), std::sin(t1_ii)};
  const std::array<double, 2> c1s = {std::cos(t1_i), std::cos(t1_ii)};
  for (std::size_t p = 0; p < 4; ++p) {
    const double s1p = s1s[p / 2];
    const double c1p = c1s[p / 2];
    const double s23 = std::sin(t2[p] + t3[p]);
    const double c23 = std::cos(t2[p] + t3[p]);
    const double m = e(0, 2) * s23 * c1p + e(1, 2) * s23 * s1p + e(2, 2) * c23;
    const double t4 =
        std::atan2(e(1, 2) * c1p - e(0, 2) * s1p, e(0, 2) * c23 * c1p + e(1, 2) * c23 * s1p - e(2, 2) * s23);
    const double t5 = std::atan2(std::sqrt(1.0 - m * m), m);
    const double t6 = std::atan2(e(0, 1) * s23 * c1p + e(1, 1) * s23 * s1p + e(2, 1) * c23,
                                 -e(0, 0) * s23 * c1p - e(1, 0) * s23 * s1p - e(2, 0) * c23);
    const std::array<double, 6> first = {t1[p], t2[p], t3[p], t4, t5, t6};
    const std::array<double, 6> second = {t1[p], t2[p], t3[p], t4 + kPi, -t5, t6 - kPi};
    for (std::size_t i = 0; i < 6; ++i) {
      q[p][i] = g.sign[i] * (first[i] - g.offset[i]);
      q[p + 4][i] = g.sign[i] * (second[i] - g.offset[i]);
    }
  }
}

}  // namespace deflex::bench
