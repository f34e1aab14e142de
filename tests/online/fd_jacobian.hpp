// Test helper shared by the online and EGM tests: the geometric Jacobian of the WAP by central
// differences of forward kinematics (position and rotation vector), independent of the analytic
// Jacobian the compensator uses.
#pragma once

#include <Eigen/Geometry>

#include "deflex/model/kinematics.hpp"

namespace deflex::test {

inline Jacobian fd_wap_jacobian(const RobotModel& m, const JointVector& q) {
  Workspace ws(m);
  Jacobian J(6, m.dof());
  const double h = 1e-6;
  for (int i = 0; i < m.dof(); ++i) {
    JointVector qp = q, qm = q;
    qp[i] += h;
    qm[i] -= h;
    forward_kinematics(m, ws, qp);
    const Pose a = ws.base_T_wap;
    forward_kinematics(m, ws, qm);
    const Pose b = ws.base_T_wap;
    J.block<3, 1>(0, i) = (a.translation() - b.translation()) / (2 * h);
    const Eigen::AngleAxisd d(a.linear() * b.linear().transpose());
    J.block<3, 1>(3, i) = d.axis() * d.angle() / (2 * h);
  }
  return J;
}

}  // namespace deflex::test
