// Path inverse kinematics on a ROS-Industrial URDF arm: the analytic solver serves it and the
// branch (KUKA Status) chosen at the first point is kept along the path.
#include <gtest/gtest.h>

#include "deflex/paths/path_ik.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace deflex {
namespace {

double pose_error(const Pose& a, const Pose& b) {
  return (a.translation() - b.translation()).norm() + (a.linear() - b.linear()).norm();
}

TEST(PathIkUrdf, APathOnAUrdfArmKeepsItsBranch) {
  const RobotModel m =
      load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/ros-industrial/kuka_kr120r2500pro.urdf");
  ASSERT_TRUE(has_analytic_ik(m));
  Workspace ws(m);
  JointVector q(6);
  q << 0.0, deg_to_rad(-80), deg_to_rad(100), 0.0, deg_to_rad(40), 0.0;
  const Pose start = tcp_pose(m, ws, q);
  std::vector<Pose> poses;
  for (int i = 0; i <= 50; ++i) {  // 1 m sideways, tool orientation held
    Pose p = start;
    p.translation().y() += 0.02 * i - 0.5;
    poses.push_back(p);
  }
  IkRequest first;
  first.seed = q;
  const JointPath path = solve_path_ik(m, poses, first);
  const KukaConfiguration s0 = kuka_configuration(m, ws, path.q.front());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    EXPECT_LT(pose_error(tcp_pose(m, ws, path.q[i]), poses[i]), 1e-9) << i;
    EXPECT_EQ(kuka_configuration(m, ws, path.q[i]).status, s0.status) << i;
  }
}

}  // namespace
}  // namespace deflex
