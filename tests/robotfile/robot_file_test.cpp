// Robot files: the YAML format (units, frames, round trip), URDF chains, and every malformed-file
// error naming the file, the line and the field.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "model/test_robots.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("deflex_model_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  return p.string();
}

const char* const kGood = R"(deflex_robot: 1
name: two-link
units: {length: mm, angle: deg}
kinematics:
  convention: standard_dh
  joints:
    - {a: 800, alpha: 0, d: 0, min: -170, max: 170}
    - {a: 600, alpha: 0, d: 0, min: -170, max: 170}
joint_stiffness_Nm_per_rad: [2.0e5, 5.0e4]
)";

void expect_error(const std::string& text, const std::vector<std::string>& fragments) {
  try {
    (void)load_robot_yaml_text(text, "robot.yaml");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const ModelError& e) {
    const std::string msg = e.what();
    for (const auto& f : fragments) {
      EXPECT_NE(msg.find(f), std::string::npos) << "message '" << msg << "' lacks '" << f << "'";
    }
  }
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

TEST(RobotFile, UnitsAreApplied) {
  const RobotModel m = load_robot_yaml_text(kGood, "robot.yaml");
  Workspace ws(m);
  const Pose T = tcp_pose(m, ws, JointVector::Zero(2));
  EXPECT_NEAR(T.translation().x(), 1.4, 1e-12);  // 800 mm + 600 mm
  EXPECT_NEAR(m.upper_limits()[0], deg_to_rad(170), 1e-12);
  EXPECT_DOUBLE_EQ(m.stiffness()[1], 5.0e4);
}

TEST(RobotFile, MalformedFilesNameTheFieldAndLine) {
  expect_error(replace(kGood, "a: 600", "a: abc"), {"robot.yaml:8", "kinematics.joints[2].a", "not a number"});
  expect_error(replace(kGood, "a: 600", "a: nan"), {"kinematics.joints[2].a", "not a finite number"});
  expect_error(replace(kGood, "[2.0e5, 5.0e4]", "[2.0e5]"), {"joint_stiffness_Nm_per_rad", "expected 2 numbers"});
  expect_error(replace(kGood, "5.0e4]", "-5.0e4]"), {"joint_stiffness_Nm_per_rad[2]", "positive"});
  expect_error(replace(kGood, "5.0e4]", "0]"), {"joint_stiffness_Nm_per_rad[2]", "positive"});
  expect_error(replace(kGood, "length: mm", "length: inch"), {"units.length", "unknown length unit 'inch'"});
  expect_error(replace(kGood, "units: {length: mm, angle: deg}\n", ""), {"units"});
  expect_error(replace(kGood, "min: -170, max: 170}\n    - {a: 600", "min: 170, max: -170}\n    - {a: 600"),
               {"kinematics.joints[1]", "'min' must be below 'max'"});
  expect_error(replace(kGood, "name: two-link", "name: two-link\nstifness: 3"), {"stifness", "unknown field"});
  expect_error(replace(kGood, "standard_dh", "craig"), {"kinematics.convention", "unknown convention 'craig'"});
  expect_error(replace(kGood, "d: 0, min: -170, max: 170}\n    - {a: 600", "min: -170, max: 170}\n    - {a: 600"),
               {"kinematics.joints[1].d", "missing"});
  expect_error("deflex_robot: 1\nname: [unclosed\n", {"robot.yaml:", "YAML syntax error"});
  expect_error(replace(kGood, "deflex_robot: 1", "deflex_robot: 7"), {"deflex_robot", "version 7"});
  expect_error(std::string(kGood) + "tool_frame: {position: [0, 0, 100], quaternion_wxyz: [1, 1, 0, 0]}\n",
               {"tool_frame.quaternion_wxyz", "unit length"});
  expect_error(std::string(kGood) + "tool_frame: {position: [0, 0], quaternion_wxyz: [1, 0, 0, 0]}\n",
               {"tool_frame.position", "expected 3 numbers"});
}

TEST(RobotFile, MissingFileAndUnknownExtension) {
  EXPECT_THROW((void)load_robot("/nonexistent/robot.yaml"), ModelError);
  try {
    (void)load_robot("robot.json");
    ADD_FAILURE();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown robot file type '.json'"), std::string::npos);
  }
}

TEST(RobotFile, WrittenYamlReadsBackToTheSameRobot) {
  const RobotModel a = test::modified_dh_arm();
  const std::string path = write_temp("roundtrip.yaml", robot_to_yaml(a));
  const RobotModel b = load_robot(path);
  Workspace wa(a);
  Workspace wb(b);
  JointVector q(6);
  q << 0.3, -0.2, 0.5, 1.0, -0.7, 2.0;
  EXPECT_LT(pose_difference(tcp_pose(a, wa, q), tcp_pose(b, wb, q)).norm(), 1e-8);
  EXPECT_LT((a.stiffness() - b.stiffness()).norm(), 1e-3);
  EXPECT_LT((a.lower_limits() - b.lower_limits()).norm(), 1e-8);
  fs::remove(path);
}

TEST(RobotFile, BuiltinIrb6700HasItsDocumentedNumbers) {
  const RobotModel m = builtin_irb6700();
  EXPECT_EQ(m.dof(), 6);
  EXPECT_DOUBLE_EQ(m.stiffness()[0], 3.0e6);
  EXPECT_DOUBLE_EQ(m.stiffness()[5], 3.0e5);
  EXPECT_NEAR(rad_to_deg(m.lower_limits()[1]), -65.0, 1e-12);
  EXPECT_NEAR(rad_to_deg(m.upper_limits()[2]), 70.0, 1e-12);
  // Joint speed limits, deg/s, as the file's comment cites them.
  const double speeds_deg_s[6] = {100, 90, 90, 170, 120, 190};
  ASSERT_TRUE(m.has_max_speed());
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(m.max_speed()[i], speeds_deg_s[i] * kPi / 180.0, 1e-12) << "joint " << i + 1;
  }
}

TEST(RobotFile, JointSpeedLimitsInTheFileUnitAndUnknownWhenAbsent) {
  const RobotModel none = load_robot_yaml_text(kGood, "robot.yaml");
  EXPECT_FALSE(none.has_max_speed());
  EXPECT_TRUE(std::isinf(none.max_speed()[0]));
  const RobotModel deg = load_robot_yaml_text(
      replace(kGood, "min: -170, max: 170}\n    - {a: 600", "min: -170, max: 170, max_speed: 45}\n    - {a: 600"),
      "robot.yaml");
  EXPECT_NEAR(deg.max_speed()[0], kPi / 4.0, 1e-12);  // 45 deg/s
  EXPECT_TRUE(std::isinf(deg.max_speed()[1]));
  expect_error(
      replace(kGood, "min: -170, max: 170}\n    - {a: 600", "min: -170, max: 170, max_speed: -3}\n    - {a: 600"),
      {"robot.yaml:7", "kinematics.joints[1].max_speed", "positive"});
  // Written and read back: the limit survives (robot_to_yaml writes degrees per second).
  const std::string path = write_temp("speed_roundtrip.yaml", robot_to_yaml(builtin_irb6700()));
  const RobotModel back = load_robot(path);
  EXPECT_LT((back.max_speed() - builtin_irb6700().max_speed()).norm(), 1e-9);
  fs::remove(path);
}

// The IRB6700 written as a URDF by hand from the published axis positions (not from the DH table):
// an independent path to the same kinematics.
const char* const kIrbUrdf = R"(<?xml version="1.0"?>
<robot name="irb6700_urdf">
  <link name="base_link"/><link name="link1"/><link name="link2"/><link name="link3"/>
  <link name="link4"/><link name="link5"/><link name="link6"/><link name="tool0"/>
  <joint name="joint_1" type="revolute"><parent link="base_link"/><child link="link1"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-2.967" upper="2.967" effort="1" velocity="1"/></joint>
  <joint name="joint_2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.320 0 0.780" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-1.134" upper="1.483" effort="1" velocity="1"/></joint>
  <joint name="joint_3" type="revolute"><parent link="link2"/><child link="link3"/>
    <origin xyz="0 0 1.145" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-3.142" upper="1.222" effort="1" velocity="1"/></joint>
  <joint name="joint_4" type="revolute"><parent link="link3"/><child link="link4"/>
    <origin xyz="0 0 0.200" rpy="0 0 0"/><axis xyz="1 0 0"/><limit lower="-5.236" upper="5.236" effort="1" velocity="1"/></joint>
  <joint name="joint_5" type="revolute"><parent link="link4"/><child link="link5"/>
    <origin xyz="1.2125 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-2.269" upper="2.269" effort="1" velocity="1"/></joint>
  <joint name="joint_6" type="revolute"><parent link="link5"/><child link="link6"/>
    <origin xyz="0.250 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/><limit lower="-6.283" upper="6.283" effort="1" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="link6"/><child link="tool0"/>
    <origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/></joint>
</robot>
)";

TEST(RobotFile, UrdfChainMatchesTheDhModel) {
  const std::string path = write_temp("irb.urdf", kIrbUrdf);
  const RobotModel urdf = load_robot(path);
  EXPECT_FALSE(urdf.has_stiffness());
  EXPECT_DOUBLE_EQ(urdf.max_speed()[0], 1.0);  // <limit velocity="1"/>, rad/s
  EXPECT_THROW((void)urdf.stiffness(), ModelError);
  const RobotModel dh = builtin_irb6700();
  Workspace wu(urdf);
  Workspace wd(dh);
  for (const auto& qa : {std::array<double, 6>{0, 0, 0, 0, 0, 0}, std::array<double, 6>{0.3, 0.2, -0.4, 1.0, 0.6, -2.0},
                         std::array<double, 6>{-1.0, -0.5, 0.8, -2.0, -1.2, 3.0}}) {
    JointVector q(6);
    for (int i = 0; i < 6; ++i) {
      q[i] = qa[static_cast<std::size_t>(i)];
    }
    EXPECT_LT(pose_difference(tcp_pose(urdf, wu, q), tcp_pose(dh, wd, q)).norm(), 1e-12);
  }
  // The same URDF through a deflex YAML that adds the stiffness.
  const std::string yaml_path =
      write_temp("irb_urdf.yaml", std::string("deflex_robot: 1\nunits: {length: m, angle: deg}\n"
                                              "kinematics: {convention: urdf, file: ") +
                                      path + "}\njoint_stiffness_Nm_per_rad: [1, 2, 3, 4, 5, 6]\n");
  const RobotModel with_k = load_robot(yaml_path);
  EXPECT_DOUBLE_EQ(with_k.stiffness()[2], 3.0);
  fs::remove(path);
  fs::remove(yaml_path);
}

TEST(RobotFile, UrdfErrors) {
  const std::string prismatic = write_temp(
      "prismatic.urdf",
      "<robot name='p'><link name='a'/><link name='b'/><joint name='slide' type='prismatic'><parent link='a'/>"
      "<child link='b'/><axis xyz='1 0 0'/><limit lower='0' upper='1' effort='1' velocity='1'/></joint></robot>");
  try {
    (void)load_robot(prismatic);
    ADD_FAILURE();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'slide'"), std::string::npos) << e.what();
  }
  const std::string garbage = write_temp("garbage.urdf", "<robot name='x'><link name=");
  EXPECT_THROW((void)load_robot(garbage), ModelError);
  fs::remove(prismatic);
  fs::remove(garbage);
}

}  // namespace
}  // namespace deflex
