// A ROS-Industrial URDF given bare to the command line: the chain note, stiffness from
// --stiffness-Nm-per-rad, and deflect refusing a robot without stiffness (exit code 2).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace deflex {
namespace {

using test::run_cli;

const std::string kUrdf = std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/ros-industrial/abb_irb6700_235_265.urdf";

TEST(CliBareUrdf, LoadsWithANoteNamingTheChainAndTheIgnoredJoints) {
  const auto r = run_cli("fk --robot " + kUrdf + " --joints-deg 0,0,0,0,0,0 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("deflex fk: note: chain base_link -> tool0"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("piston_joint (prismatic, mimics joint_2)"), std::string::npos) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  // abb_irb6700_support: tool0 at 0.32 + 1.1825 + 0.165 + 0.035 = 1.7025 m ahead, 0.288 + 0.492 + 1.135 + 0.2 up.
  EXPECT_NEAR(doc["position_m"][0].get<double>(), 1.7025, 1e-12);
  EXPECT_NEAR(doc["position_m"][2].get<double>(), 2.115, 1e-12);
}

TEST(CliBareUrdf, DeflectRefusesARobotWithoutStiffness) {
  const auto r = run_cli("deflect --robot " + kUrdf + " --joints-deg 0,10,10,0,30,0 --wrench 0,0,-500,0,0,0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("has no joint stiffness"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--stiffness-Nm-per-rad"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(CliBareUrdf, StiffnessOnTheCommandLineGivesTheClosedFormDeflection) {
  // Arm stretched forward (joints 2 and 3 at zero: upper arm vertical, forearm horizontal) and a
  // vertical force at tool0: only joints 2, 3 and 5 turn, by F * lever / k, the lever being the
  // horizontal distance from each axis to tool0 (the published geometry, not deflex's Jacobian).
  const double k[6] = {3e6, 2.5e6, 1.8e6, 6e5, 5e5, 3e5};
  const auto r = run_cli("deflect --robot " + kUrdf +
                         " --joints-deg 0,0,0,0,0,0 --wrench 0,0,-500,0,0,0 --json --stiffness-Nm-per-rad "
                         "3e6,2.5e6,1.8e6,6e5,5e5,3e5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto d = nlohmann::json::parse(r.out);
  const double lever2 = 1.1825 + 0.165 + 0.035;  // axis 2 and axis 3 are both 1.3825 m behind tool0
  const double lever5 = 0.165 + 0.035;
  // A downward force at tool0 turns joints 2 and 3 about +y by +F*lever/k (URDF axes +y).
  EXPECT_NEAR(d["dtheta_rad"][1].get<double>(), 500.0 * lever2 / k[1], 1e-12);
  EXPECT_NEAR(d["dtheta_rad"][2].get<double>(), 500.0 * lever2 / k[2], 1e-12);
  EXPECT_NEAR(d["dtheta_rad"][4].get<double>(), 500.0 * lever5 / k[4], 1e-12);
  EXPECT_NEAR(d["dtheta_rad"][0].get<double>(), 0.0, 1e-15);
  const auto bad = run_cli("deflect --robot " + kUrdf +
                           " --joints-deg 0,0,0,0,0,0 --wrench 0,0,-500,0,0,0 "
                           "--stiffness-Nm-per-rad 1,2,3");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("option --stiffness-Nm-per-rad: expected 6"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace deflex
