// Broken preconditions refused in every build type (the tests run in Release in CI): a deflection on a
// robot without stiffness, joint values of the wrong count, a workspace of another robot. Before,
// the first gave 1e+227 rad in Release and the second read past the end of q.
#include <string>

#include <gtest/gtest.h>

#include "deflex/model/compliance.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

RobotModel bare_urdf() {
  return load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/ros-industrial/kuka_kr120r2500pro.urdf");
}

TEST(Preconditions, DeflectionWithoutStiffnessIsRefused) {
  const RobotModel robot = bare_urdf();
  ASSERT_FALSE(robot.has_stiffness());
  Workspace ws(robot);
  const JointVector q = JointVector::Constant(robot.dof(), 0.3);
  Wrench w;
  w << 0.0, 0.0, -500.0, 0.0, 0.0, 0.0;
  JointVector dtheta, q_cmd, q_actual;
  EXPECT_THROW(joint_deflection(robot, ws, q, w, dtheta), ModelError);
  EXPECT_THROW((void)tcp_deflection(robot, ws, q, w), ModelError);
  EXPECT_THROW((void)cartesian_compliance(robot, ws, q), ModelError);
  EXPECT_THROW(compensated_configuration(robot, ws, q, w, q_cmd), ModelError);
  EXPECT_THROW((void)deflected_configuration(robot, ws, q, w, q_actual), ModelError);
  EXPECT_NE(test::error_of([&] { joint_deflection(robot, ws, q, w, dtheta); }).find("kuka_kr120r2500pro.urdf"),
            std::string::npos);
}

TEST(Preconditions, JointValuesOfTheWrongCountAreRefused) {
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);
  const JointVector five = JointVector::Constant(5, 0.1);
  const JointVector seven = JointVector::Constant(7, 0.1);
  EXPECT_THROW(forward_kinematics(robot, ws, five), InputError);
  EXPECT_THROW(forward_kinematics(robot, ws, seven), InputError);
  EXPECT_THROW((void)tcp_pose(robot, ws, five), InputError);
  Jacobian J(6, 6);
  EXPECT_THROW(jacobian(robot, ws, five, EndPoint::kTcp, J), InputError);
  Wrench w = Wrench::Zero();
  JointVector dtheta;
  EXPECT_THROW(joint_deflection(robot, ws, five, w, dtheta), InputError);
  EXPECT_NE(test::error_of([&] { forward_kinematics(robot, ws, five); }).find("5 joint values"), std::string::npos);
}

TEST(Preconditions, AWorkspaceOfAnotherRobotIsRefused) {
  const RobotModel six = builtin_irb6700();
  RobotDescription d = six.description();
  d.joints.pop_back();
  d.dh.clear();
  d.dh_convention.reset();
  d.stiffness_nm_per_rad.pop_back();
  const RobotModel five(d);
  Workspace ws_five(five);
  const JointVector q = JointVector::Constant(6, 0.1);
  EXPECT_NE(
      test::error_of([&] { forward_kinematics(six, ws_five, q); }).find("workspace was made for a robot of 5 joints"),
      std::string::npos);
}

}  // namespace
}  // namespace deflex
