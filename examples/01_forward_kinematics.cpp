// Example 1: load the built-in ABB IRB 6700, compute the TCP pose and the Jacobian at a
// configuration. The model is immutable; the workspace holds every buffer (no allocation per call).
#include <cstdio>

#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"

int main() {
  using namespace deflex;
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);

  JointVector q(6);
  q << 0.0, deg_to_rad(30), deg_to_rad(10), 0.0, deg_to_rad(50), 0.0;  // rad inside, degrees at the edge
  Jacobian J;
  jacobian(robot, ws, q, EndPoint::kTcp, J);

  const Vector3 p = ws.base_T_tcp.translation();
  std::printf("%s\nTCP at q = [0, 30, 10, 0, 50, 0] deg: (%.1f, %.1f, %.1f) mm\n", robot.name().c_str(), p.x() * 1e3,
              p.y() * 1e3, p.z() * 1e3);
  std::printf("joint 1 moves the TCP by %.3f m per rad (its lever arm)\n", J.col(0).head<3>().norm());
  return p.allFinite() ? 0 : 1;
}
