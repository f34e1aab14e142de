// The shipped synthetic example (examples/identify/) still identifies the true stiffness within
// the reported standard errors, starting from the nominal robot file.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace deflex {
namespace {

TEST(ExampleData, Kr210SyntheticMeasurementsGiveTheTrueStiffnessWithinTheStandardErrors) {
  const std::string dir = std::string(DEFLEX_SOURCE_DIR) + "/examples/";
  const RobotModel nominal = load_robot(dir + "robots/kuka_kr210_r2700.yaml");
  const RobotModel truth = load_robot(dir + "identify/kr210_true_stiffness.yaml");
  const auto data = read_stiffness_measurements(dir + "identify/kr210_synthetic_measurements.csv");
  const StiffnessEstimate est = identify_stiffness(nominal, data);
  EXPECT_TRUE(est.unidentifiable_joints.empty());
  EXPECT_TRUE(est.rejected_measurements.empty());
  EXPECT_NEAR(est.residual_rms_m, 10e-6, 2e-6);  // the 0.01 mm noise the file was made with
  for (int j = 0; j < 6; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    EXPECT_LT(std::abs(est.stiffness_nm_per_rad[ju] - truth.stiffness()[j]), 3.0 * est.std_error_nm_per_rad[ju])
        << "joint " << j + 1;
    // ... and far from the nominal values it started with (the data decide, not the file).
    EXPECT_GT(std::abs(est.stiffness_nm_per_rad[ju] - nominal.stiffness()[j]), 5.0 * est.std_error_nm_per_rad[ju])
        << "joint " << j + 1;
  }
}

}  // namespace
}  // namespace deflex
