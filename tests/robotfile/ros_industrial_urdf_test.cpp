// URDFs as ROS-Industrial ships them (examples/robots/ros-industrial) load bare, pick
// base_link -> tool0, list what they leave out, and agree with a URDF FK written independently of
// the loader; broken trees fail naming the file, the line and the joint.
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <unistd.h>

#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "model/urdf_reference.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

std::string urdf_fixture(const std::string& name) {
  return std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/ros-industrial/" + name;
}

struct Fixture {
  const char* file;
  const char* ignored;  // a joint the note must list as left out ("" when none)
};

const Fixture kFixtures[] = {
    {"abb_irb6700_235_265.urdf", "piston_joint (prismatic, mimics joint_2)"},
    {"kuka_kr120r2500pro.urdf", "base_link-base (fixed)"},
    {"kuka_kr210_r3100_2.urdf", "joint_6-flange (fixed)"},
    {"fanuc_m10ia.urdf", ""},
    {"staubli_tx2_60l.urdf", "base_link-base (fixed)"},
};

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) {
    s += x + "\n";
  }
  return s;
}

TEST(RosIndustrialUrdf, EachLoadsBareAsBaseLinkToTool0) {
  for (const Fixture& f : kFixtures) {
    const RobotModel m = load_robot(urdf_fixture(f.file));
    EXPECT_EQ(m.dof(), 6) << f.file;
    EXPECT_FALSE(m.has_stiffness()) << f.file;
    EXPECT_EQ(m.description().urdf_base_link, "base_link") << f.file;
    EXPECT_EQ(m.description().urdf_tip_link, "tool0") << f.file;
    const std::string notes = joined(m.description().notes);
    EXPECT_NE(notes.find("base_link -> tool0"), std::string::npos) << notes;
    if (std::string(f.ignored).empty()) {
      EXPECT_EQ(notes.find("ignored"), std::string::npos) << notes;
    } else {
      EXPECT_NE(notes.find(f.ignored), std::string::npos) << f.file << "\n" << notes;
    }
    EXPECT_TRUE(m.has_max_speed()) << f.file;
  }
}

TEST(RosIndustrialUrdf, ForwardKinematicsAgreesWithAnIndependentUrdfReading) {
  std::mt19937_64 rng(13);
  for (const Fixture& f : kFixtures) {
    const RobotModel m = load_robot(urdf_fixture(f.file));
    const auto chain = test::reference_chain(urdf_fixture(f.file), "base_link", "tool0");
    Workspace ws(m);
    for (int s = 0; s < 200; ++s) {
      JointVector q(6);
      std::vector<double> qv(6);
      for (int i = 0; i < 6; ++i) {
        q[i] = qv[static_cast<std::size_t>(i)] =
            std::uniform_real_distribution<double>(m.lower_limits()[i], m.upper_limits()[i])(rng);
      }
      const Pose expected = test::reference_fk(chain, qv);
      const Pose got = tcp_pose(m, ws, q);
      ASSERT_LT((got.translation() - expected.translation()).norm(), 1e-12) << f.file << " sample " << s;
      ASSERT_LT((got.linear() - expected.linear()).norm(), 1e-12) << f.file << " sample " << s;
    }
  }
}

TEST(RosIndustrialUrdf, PublishedJointLimitsAndSpeedsComeThrough) {
  // abb_irb6700_support: joint 2 from -65 to 85 deg, joint 6 at 190 deg/s.
  const RobotModel abb = load_robot(urdf_fixture("abb_irb6700_235_265.urdf"));
  EXPECT_NEAR(rad_to_deg(abb.lower_limits()[1]), -65.0, 1e-12);
  EXPECT_NEAR(rad_to_deg(abb.upper_limits()[1]), 85.0, 1e-12);
  EXPECT_NEAR(rad_to_deg(abb.max_speed()[5]), 190.0, 1e-12);
  // kuka_kr210_support: A2 from -140 to -5 deg.
  const RobotModel kuka = load_robot(urdf_fixture("kuka_kr210_r3100_2.urdf"));
  EXPECT_NEAR(rad_to_deg(kuka.lower_limits()[1]), -140.0, 1e-12);
  EXPECT_NEAR(rad_to_deg(kuka.upper_limits()[1]), -5.0, 1e-12);
}

TEST(RosIndustrialUrdf, NamedEndsInAYamlOverlayOverrideTheConvention) {
  const std::string yaml = (fs::temp_directory_path() / ("deflex_ri_" + std::to_string(::getpid()) + ".yaml")).string();
  std::ofstream(yaml) << "deflex_robot: 1\nunits: {length: m, angle: deg}\nkinematics: {convention: urdf, file: "
                      << urdf_fixture("kuka_kr120r2500pro.urdf")
                      << ", tip_link: flange}\njoint_stiffness_Nm_per_rad: [1e6, 1e6, 1e6, 1e5, 1e5, 1e5]\n";
  const RobotModel m = load_robot(yaml);
  EXPECT_EQ(m.description().urdf_tip_link, "flange");
  EXPECT_TRUE(m.has_stiffness());
  Workspace ws(m);
  const auto chain = test::reference_chain(urdf_fixture("kuka_kr120r2500pro.urdf"), "base_link", "flange");
  const std::vector<double> qv{0.1, -1.2, 1.4, 0.3, -0.5, 0.7};
  JointVector q(6);
  for (int i = 0; i < 6; ++i) {
    q[i] = qv[static_cast<std::size_t>(i)];
  }
  EXPECT_LT((tcp_pose(m, ws, q).matrix() - test::reference_fk(chain, qv).matrix()).norm(), 1e-12);
  fs::remove(yaml);
}

// ---------------------------------------------------------------------------------------------
// Broken trees.

std::string write_urdf(const std::string& name, const std::string& body) {
  const fs::path p = fs::temp_directory_path() / ("deflex_urdf_" + std::to_string(::getpid()) + "_" + name + ".urdf");
  std::ofstream(p) << "<?xml version=\"1.0\"?>\n<robot name=\"t\">\n" << body << "</robot>\n";
  return p.string();
}

std::string revolute(const std::string& name, const std::string& parent, const std::string& child,
                     const std::string& extra = "") {
  return "  <joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><origin xyz=\"0 0 0.5\"/><axis xyz=\"0 1 0\"/>" + extra +
         "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n";
}

const char* const kLinks = "  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <link name=\"c\"/>\n  <link name=\"d\"/>\n";

void expect_load_error(const std::string& name, const std::string& body, const std::vector<std::string>& fragments) {
  const std::string path = write_urdf(name, body);
  try {
    (void)load_robot(path);
    ADD_FAILURE() << name << ": loaded";
  } catch (const ModelError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    for (const auto& f : fragments) {
      EXPECT_NE(msg.find(f), std::string::npos) << name << ": '" << msg << "' lacks '" << f << "'";
    }
  }
  fs::remove(path);
}

TEST(RosIndustrialUrdf, BrokenTreesNameTheLineAndTheJoint) {
  // Lines: 1 xml, 2 robot, 3-6 links, 7.. joints.
  expect_load_error(
      "loop", std::string(kLinks) + revolute("j1", "a", "b") + revolute("j2", "b", "c") + revolute("j3", "c", "b"),
      {":9:", "link 'b' has two parents", "'j1' (line 7)", "'j3' (line 9)"});
  expect_load_error("cycle", std::string(kLinks) + revolute("j1", "a", "b") + revolute("j2", "b", "a"),
                    {"closes a loop", "joint 'j"});
  expect_load_error("mimic_on_chain",
                    std::string(kLinks) + revolute("j1", "a", "b") +
                        revolute("j2", "b", "c", "<mimic joint=\"j1\" multiplier=\"1\"/>") + revolute("j3", "c", "d"),
                    {":8:", "joint 'j2'", "mimics joint 'j1'"});
  expect_load_error("no_movable",
                    std::string(kLinks) +
                        "  <joint name=\"f\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>\n"
                        "  <joint name=\"g\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n"
                        "  <joint name=\"h\" type=\"fixed\"><parent link=\"c\"/><child link=\"d\"/></joint>\n",
                    {"no movable joint"});
  expect_load_error(
      "branches", std::string(kLinks) + revolute("j1", "a", "b") + revolute("j2", "b", "c") + revolute("j3", "b", "d"),
      {"2 leaves", "'c'", "'d'", "tip_link", "branches into several arms"});
  expect_load_error("unknown_link", std::string(kLinks) + revolute("j1", "a", "b") + revolute("j2", "b", "x"),
                    {":8:", "joint 'j2'", "child link 'x' is not defined"});
  expect_load_error("two_roots", std::string(kLinks) + revolute("j1", "a", "b") + revolute("j2", "c", "d"),
                    {"2 root links", "'a' (line 3)", "'c' (line 5)"});
  expect_load_error("prismatic_on_chain",
                    std::string(kLinks) + revolute("j1", "a", "b") +
                        "  <joint name=\"slide\" type=\"prismatic\"><parent link=\"b\"/><child link=\"c\"/><axis "
                        "xyz=\"1 0 0\"/><limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n" +
                        revolute("j3", "c", "d"),
                    {":8:", "joint 'slide'", "prismatic"});
  expect_load_error("not_xml", "  <link name=\"a\">\n", {"not well-formed XML"});
}

TEST(RosIndustrialUrdf, MimicAndPrismaticJointsOffTheChainAreIgnoredWithANote) {
  // A chain a-b-c with a mimic prismatic slide hanging off b: the slide is not counted as an axis.
  const std::string path = write_urdf(
      "offchain", std::string(kLinks) + revolute("j1", "a", "b") + revolute("j2", "b", "c") +
                      "  <joint name=\"slide\" type=\"prismatic\"><parent link=\"b\"/><child link=\"d\"/>"
                      "<axis xyz=\"1 0 0\"/><mimic joint=\"j1\"/><limit lower=\"0\" upper=\"1\" effort=\"1\" "
                      "velocity=\"1\"/></joint>\n");
  const RobotModel m = load_robot(path);
  EXPECT_EQ(m.dof(), 2);
  EXPECT_EQ(m.description().urdf_tip_link, "c");
  const std::string notes = joined(m.description().notes);
  EXPECT_NE(notes.find("slide (prismatic, mimics j1)"), std::string::npos) << notes;
  fs::remove(path);
}

}  // namespace
}  // namespace deflex
