// deflex identify and deflex evaluate run as a user runs them, checked against values made outside
// the code under test: the shipped synthetic example's true stiffness, and a circle offset by a
// known amount (closed-form distance).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::run_cli;

const std::string kSrc = DEFLEX_SOURCE_DIR;

TEST(CliIdentify, RecoversTheSecondArmsTrueStiffnessWithinItsStandardErrors) {
  const auto r = run_cli("identify --robot " + kSrc + "/examples/robots/kuka_kr210_r2700.yaml --data " + kSrc +
                         "/examples/identify/kr210_synthetic_measurements.csv --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  const RobotModel truth = load_robot(kSrc + "/examples/identify/kr210_true_stiffness.yaml");
  ASSERT_EQ(doc["stiffness_Nm_per_rad"].size(), 6u);
  for (int j = 0; j < 6; ++j) {
    const double k = doc["stiffness_Nm_per_rad"][j].get<double>();
    const double se = doc["std_error_Nm_per_rad"][j].get<double>();
    EXPECT_LT(std::abs(k - truth.stiffness()[j]), 4.0 * se) << "joint " << j + 1;
    EXPECT_LT(se / k, 0.05) << "joint " << j + 1;
  }
  EXPECT_TRUE(doc["unidentifiable_joints"].empty());
}

TEST(CliIdentify, BadMeasurementFileNamesLineAndColumn) {
  const fs::path p = fs::temp_directory_path() / ("deflex_bad_meas_" + std::to_string(::getpid()) + ".csv");
  std::ofstream(p) << "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,dx_mm,dy_mm,dz_mm\n"
                      "0,30,10,0,50,0,100,0,0,0,0,0,0.1,0,0\n"
                      "0,30,10,0,50,0,100,0,nan,0,0,0,0.1,0,0\n";
  const auto r = run_cli("identify --robot builtin --data " + p.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(p.string() + ":3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("fz_N"), std::string::npos) << r.err;
  fs::remove(p);
}

void write_circle(const fs::path& p, double radius_mm, double z_mm, int samples) {
  std::ofstream out(p);
  out << "t_s,x_mm,y_mm,z_mm\n";
  for (int i = 0; i < samples; ++i) {
    const double a = 2.0 * kPi * i / (samples - 1);
    out << i * 1e-3 << "," << 1500.0 + radius_mm * std::cos(a) << "," << radius_mm * std::sin(a) << "," << z_mm << "\n";
  }
}

TEST(CliEvaluate, MeanDeformationOfAnOffsetCircleIsTheOffset) {
  const fs::path dir = fs::temp_directory_path() / ("deflex_eval_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // Loaded: radius 0.3 mm larger and 0.4 mm higher: every point is sqrt(0.3^2 + 0.4^2) = 0.5 mm
  // from the unloaded circle (the chord sag of 5000 samples, 2e-6 mm, is negligible).
  write_circle(dir / "unloaded.csv", 100.0, 1000.0, 5000);
  write_circle(dir / "loaded.csv", 100.3, 1000.4, 3000);
  const auto r = run_cli("evaluate --unloaded " + (dir / "unloaded.csv").string() + " --loaded " +
                         (dir / "loaded.csv").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_NEAR(doc["mean_deformation_mm"].get<double>(), 0.5, 1e-4) << r.out;

  std::ofstream(dir / "bad.csv") << "t_s,x_mm,y_mm,z_mm\n0,1,2,3\n0.001,1,nan,3\n";
  const auto bad =
      run_cli("evaluate --unloaded " + (dir / "unloaded.csv").string() + " --loaded " + (dir / "bad.csv").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("bad.csv:3"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("y_mm"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace deflex
