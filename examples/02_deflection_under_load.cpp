// Example 2: how far does the arm give under a process force? Joint deflection, TCP deflection, and
// the softest and stiffest directions from the Cartesian compliance matrix.
#include <cstdio>

#include <Eigen/Eigenvalues>

#include "deflex/model/compliance.hpp"
#include "deflex/robotfile/robot_io.hpp"

int main() {
  using namespace deflex;
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);
  JointVector q(6);
  q << 0.0, deg_to_rad(30), deg_to_rad(10), 0.0, deg_to_rad(50), 0.0;

  Wrench w = Wrench::Zero();
  w[2] = -650.0;  // 650 N pushing down on the TCP (base frame)
  const Displacement dx = tcp_deflection(robot, ws, q, w);
  std::printf("650 N down: TCP moves (%.3f, %.3f, %.3f) mm\n", dx[0] * 1e3, dx[1] * 1e3, dx[2] * 1e3);

  // Translational compliance block (m/N): its eigenvectors are the principal directions.
  const Matrix6 C = cartesian_compliance(robot, ws, q);
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(C.topLeftCorner<3, 3>());
  const Vector3 soft = eig.eigenvectors().col(2);
  std::printf("softest direction (%.2f, %.2f, %.2f): %.3f mm/kN; stiffest: %.3f mm/kN\n", soft.x(), soft.y(), soft.z(),
              eig.eigenvalues()[2] * 1e6, eig.eigenvalues()[0] * 1e6);
  return dx.allFinite() ? 0 : 1;
}
