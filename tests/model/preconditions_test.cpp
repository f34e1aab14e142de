// Broken preconditions refused in every build type (the tests run in Release in CI): a deflection or a
// compliance on a robot without stiffness, a stiffness outside the robot file's range however it is
// given, joint values of the wrong count, a workspace of another robot, a seed of the wrong size; and
// the seed orders every IK solution as it orders Python's ik().
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

std::string fmt_list(const std::vector<double>& v) {
  std::string out;
  for (const double x : v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", x);
    out += (out.empty() ? "" : ", ") + std::string(text);
  }
  return out;
}

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

TEST(Preconditions, ComplianceOfARobotWithoutStiffnessIsRefusedAsItsStiffnessIs) {
  const RobotModel robot = bare_urdf();
  ASSERT_FALSE(robot.has_stiffness());
  EXPECT_THROW((void)robot.stiffness(), ModelError);
  EXPECT_THROW((void)robot.compliance(), ModelError);
  const std::string why = test::error_of([&] { (void)robot.compliance(); });
  EXPECT_NE(why.find("kuka_kr120r2500pro.urdf"), std::string::npos) << why;
  EXPECT_NE(why.find("no joint stiffness"), std::string::npos) << why;
  // With stiffness, 1/k of what was given.
  const RobotModel stiff = robot.with_stiffness(std::vector<double>(6, 2.0e6), "test");
  EXPECT_DOUBLE_EQ(stiff.compliance()[3], 0.5e-6);
}

// The built-in robot's file with its stiffness list replaced.
std::string builtin_yaml_with_stiffness(const std::string& list) {
  std::ifstream in(std::string(DEFLEX_SOURCE_DIR) + "/data/robots/abb_irb6700_300_270.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string key = "joint_stiffness_Nm_per_rad: [";
  const auto at = yaml.find(key);
  const auto end = yaml.find(']', at);
  return yaml.replace(at + key.size(), end - at - key.size(), list);
}

TEST(Preconditions, AStiffnessOutsideTheRobotFilesRangeIsRefusedHoweverItIsGiven) {
  const RobotModel robot = builtin_irb6700();
  // 1e-300 Nm/rad would deflect by 1e302 rad under 100 N at 1 m; 1e11 is stiffer than any joint.
  std::vector<double> nan_stiffness = {3.0e6, kNaN, 1.8e6, 6.0e5, 5.0e5, 3.0e5};
  EXPECT_THROW((void)robot.with_stiffness(nan_stiffness, "test"), ModelError);
  for (const double k : {1e-300, 0.5, 1e11, -3e5}) {
    std::vector<double> stiffness = {3.0e6, 2.5e6, 1.8e6, 6.0e5, 5.0e5, 3.0e5};
    stiffness[1] = k;
    EXPECT_THROW((void)robot.with_stiffness(stiffness, "test"), ModelError) << k;
    const std::string from_code = test::error_of([&] { (void)robot.with_stiffness(stiffness, "test"); });
    const std::string from_file = test::error_of(
        [&] { (void)load_robot_yaml_text(builtin_yaml_with_stiffness(fmt_list(stiffness)), "robot.yaml"); });
    EXPECT_NE(from_code.find("joint_stiffness_Nm_per_rad[2]"), std::string::npos) << from_code;
    // The same range in both messages: the file's reader and the model hold the same bounds.
    EXPECT_NE(from_code.find("1..1e+10 Nm/rad"), std::string::npos) << from_code;
    EXPECT_NE(from_file.find("1..1e+10 Nm/rad"), std::string::npos) << from_file;
  }
  // The bounds themselves are accepted.
  EXPECT_NO_THROW((void)robot.with_stiffness({1.0, 1e10, 1.8e6, 6.0e5, 5.0e5, 3.0e5}, "test"));
}

TEST(Preconditions, EveryIkSolutionComesNearestTheSeedFirst) {
  const RobotModel robot = builtin_irb6700();
  Workspace ws(robot);
  JointVector q(6);
  q << 0.3, 0.4, 0.1, 1.0, 0.8, -0.5;
  const Pose target = tcp_pose(robot, ws, q);
  const std::vector<IkResult> unseeded = all_ik_solutions(robot, ws, target);
  ASSERT_GE(unseeded.size(), 4U);
  // Seeds near several of the solutions: each time the solution nearest the seed (by the largest joint
  // difference, computed here) comes first and the rest follow in order; the set is the same.
  for (std::size_t pick : {std::size_t{0}, unseeded.size() / 2, unseeded.size() - 1}) {
    IkRequest request;
    request.seed = unseeded[pick].q + JointVector::Constant(6, 0.01);
    const std::vector<IkResult> seeded = all_ik_solutions(robot, ws, target, request);
    ASSERT_EQ(seeded.size(), unseeded.size());
    std::vector<double> distance;
    for (const IkResult& r : seeded) distance.push_back((r.q - *request.seed).cwiseAbs().maxCoeff());
    EXPECT_TRUE(std::is_sorted(distance.begin(), distance.end()));
    EXPECT_LT((seeded.front().q - unseeded[pick].q).cwiseAbs().maxCoeff(), 1e-9);
    for (const IkResult& r : seeded) {
      EXPECT_LT((tcp_pose(robot, ws, r.q).translation() - target.translation()).norm(), 1e-9);
      const bool in_unseeded = std::any_of(unseeded.begin(), unseeded.end(), [&](const IkResult& u) {
        return (u.q - r.q).cwiseAbs().maxCoeff() < 1e-12;
      });
      EXPECT_TRUE(in_unseeded);
    }
  }
  IkRequest short_seed;
  short_seed.seed = JointVector::Constant(5, 0.1);
  EXPECT_THROW((void)all_ik_solutions(robot, ws, target, short_seed), InputError);
}

}  // namespace
}  // namespace deflex
