// Example 3: compensate one pose for a known wrench. The command q_cmd = q_des - K^-1 J(q_des)^T W
// is exact for the lumped model: the arm, deflecting at the configuration it really takes, lands
// on q_des. The check solves that deflection independently by fixed-point iteration.
#include <cstdio>

#include "deflex/model/compliance.hpp"
#include "deflex/robotfile/robot_io.hpp"

int main() {
  using namespace deflex;
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);
  JointVector q_des(6);
  q_des << deg_to_rad(10), deg_to_rad(35), deg_to_rad(5), deg_to_rad(20), deg_to_rad(45), deg_to_rad(-30);
  Wrench w;
  w << 350.0, -200.0, -450.0, 0.0, 0.0, 0.0;  // N, Nm in the base frame

  JointVector q_cmd;
  compensated_configuration(robot, ws, q_des, w, q_cmd);
  JointVector q_uncompensated;
  JointVector q_compensated;
  deflected_configuration(robot, ws, q_des, w, q_uncompensated);
  deflected_configuration(robot, ws, q_cmd, w, q_compensated);
  const Vector3 want = tcp_pose(robot, ws, q_des).translation();
  const double err_uc = (tcp_pose(robot, ws, q_uncompensated).translation() - want).norm();
  const double err_c = (tcp_pose(robot, ws, q_compensated).translation() - want).norm();
  std::printf("TCP error under load: uncompensated %.4f mm, compensated %.2e mm\n", err_uc * 1e3, err_c * 1e3);
  return err_c < 1e-9 && err_uc > 1e-5 ? 0 : 1;
}
