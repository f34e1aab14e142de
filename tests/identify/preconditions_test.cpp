// Broken preconditions of the identification refused in every build type (the tests run in Release
// in CI): thresholds that are not numbers in [0, 1) and a negative count of robust iterations, at
// set-up. Before, a NaN excitation threshold switched the not-excited check off without a word, a
// NaN singular-value threshold dropped every joint as "collinear" and blamed the data, and a
// negative iteration count quietly skipped the robust re-weighting the options asked for.
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

TEST(IdentifyPreconditions, ThresholdsThatAreNotAFractionAreRefusedAtSetUp) {
  const RobotModel robot = builtin_irb6700();
  for (const double bad : {kNaN, -1e-8, 1.0, std::numeric_limits<double>::infinity()}) {
    IdentificationOptions excitation;
    excitation.min_relative_excitation = bad;
    std::string error = test::error_of([&] { StiffnessIdentifier id(robot, excitation); });
    EXPECT_NE(error.find("min_relative_excitation"), std::string::npos) << bad << ": " << error;

    IdentificationOptions singular;
    singular.min_relative_singular_value = bad;
    error = test::error_of([&] { (void)identify_stiffness(robot, {}, singular); });
    EXPECT_NE(error.find("min_relative_singular_value"), std::string::npos) << bad << ": " << error;
  }
  IdentificationOptions zero;
  zero.min_relative_excitation = 0.0;
  zero.min_relative_singular_value = 0.0;
  EXPECT_NO_THROW(StiffnessIdentifier(robot, zero));
}

TEST(IdentifyPreconditions, ANegativeCountOfRobustIterationsIsRefusedAtSetUp) {
  const RobotModel robot = builtin_irb6700();
  IdentificationOptions options;
  options.max_robust_iterations = -1;
  const std::string error = test::error_of([&] { StiffnessIdentifier id(robot, options); });
  EXPECT_NE(error.find("max_robust_iterations"), std::string::npos) << error;
  options.max_robust_iterations = 0;  // least squares without re-weighting
  EXPECT_NO_THROW(StiffnessIdentifier(robot, options));
}

}  // namespace
}  // namespace deflex
