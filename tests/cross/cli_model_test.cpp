// The model subcommands of the deflex program, run as a user runs them: JSON on stdout only, units,
// exit codes, and errors that name the option, file or field.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace deflex {
namespace {

using test::run_cli;

TEST(CliModel, FkJsonIsTheOnlyThingOnStdout) {
  const auto r = run_cli("fk --joints-deg 0,0,0,0,0,0 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);  // throws if anything else is on stdout
  // Datasheet flange at all joints zero: (1782.5, 0, 2125) mm, tool0 quaternion (0.7071, 0, 0.7071, 0).
  EXPECT_NEAR(doc["position_m"][0].get<double>(), 1.7825, 1e-9);
  EXPECT_NEAR(doc["position_m"][2].get<double>(), 2.125, 1e-9);
  EXPECT_NEAR(std::abs(doc["quaternion_wxyz"][0].get<double>()), std::sqrt(0.5), 1e-9);
  EXPECT_EQ(doc["rotation_matrix"].size(), 3u);
}

TEST(CliModel, IkInvertsFkThroughTheCommandLine) {
  const auto fk = run_cli("fk --joints-deg 15,40,-20,30,60,-45 --json");
  ASSERT_EQ(fk.exit_code, 0);
  const auto f = nlohmann::json::parse(fk.out);
  std::string pos;
  std::string quat;
  for (int i = 0; i < 3; ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%.9f", i ? "," : "", f["position_m"][i].get<double>() * 1e3);
    pos += buf;
  }
  for (int i = 0; i < 4; ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%.12f", i ? "," : "", f["quaternion_wxyz"][i].get<double>());
    quat += buf;
  }
  const auto ik =
      run_cli("ik --position-mm " + pos + " --quaternion-wxyz " + quat + " --seed-deg 15,40,-20,30,60,-45 --json");
  ASSERT_EQ(ik.exit_code, 0) << ik.err;
  const auto j = nlohmann::json::parse(ik.out);
  const double want[6] = {15, 40, -20, 30, 60, -45};
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(j["joints_deg"][i].get<double>(), want[i], 1e-4);
  }
}

TEST(CliModel, DeflectGivesTheModelsFigures) {
  const auto r = run_cli("deflect --joints-deg 0,30,10,0,50,0 --wrench 0,0,-125,0,0,0 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto d = nlohmann::json::parse(r.out);
  // Independent check: the z compliance is the sum over joints of J_zj^2 / k_j, and
  // deflection = compliance matrix times wrench, so tcp_deflection_m[2] = -125 * C[2][2].
  EXPECT_NEAR(d["tcp_deflection_m"][2].get<double>(), -125.0 * d["cartesian_compliance"][2][2].get<double>(), 1e-15);
  EXPECT_NEAR(d["tcp_deflection_m"][2].get<double>(), -0.2105e-3, 0.001e-3);
  EXPECT_EQ(d["dtheta_rad"].size(), 6u);
}

TEST(CliModel, BadInputNamesTheOptionAndExitsWithTwo) {
  auto r = run_cli("fk --joints-deg 1,2,3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--joints-deg"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected 6"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());

  r = run_cli("deflect --joints-deg 0,0,0,0,0,0 --wrench 1,2,nan,0,0,0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--wrench"), std::string::npos) << r.err;

  r = run_cli("ik --position-mm 1,2,3 --quaternion-wxyz 1,1,1,1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unit quaternion"), std::string::npos) << r.err;

  r = run_cli("ik --position-mm 9000,0,0 --quaternion-wxyz 1,0,0,0 --json");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(nlohmann::json::parse(r.out)["status"], "unreachable");
}

TEST(CliModel, BadRobotFileNamesFileLineAndField) {
  const auto path =
      std::filesystem::temp_directory_path() / ("deflex_bad_robot_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(path) << "deflex_robot: 1\nunits: {length: m, angle: deg}\nkinematics:\n  convention: standard_dh\n"
                         "  joints:\n    - {a: 0.3, alpha: -90, d: zero, min: -170, max: 170}\n";
  const auto r = run_cli("fk --robot " + path.string() + " --joints-deg 0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(path.string() + ":6"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("kinematics.joints[1].d"), std::string::npos) << r.err;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace deflex
