// Identification with fewer equations than unknowns (or exactly as many) must flag every joint it
// cannot identify instead of reporting stiffness for them (issue 16: one measurement row, 3
// equations for 6 unknowns, gave six values and no flag).
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <string>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// Exact measurements of the built-in arm at `count` configurations, each under its own wrench.
std::vector<StiffnessMeasurement> exact_measurements(const RobotModel& m, int count) {
  std::vector<StiffnessMeasurement> data;
  Workspace ws(m);
  for (int i = 0; i < count; ++i) {
    StiffnessMeasurement s;
    s.q = JointVector::Zero(m.dof());
    s.q << 0.1 * i, 0.5 + 0.05 * i, 0.2, 0.3 * i, 0.8, 0.1;
    s.wrench_base << 300.0 - 50.0 * i, 200.0, -500.0, 40.0 * i, 20.0, 10.0;
    s.dp_m = tcp_deflection(m, ws, s.q, s.wrench_base).head<3>();
    data.push_back(s);
  }
  return data;
}

// One row of 3 equations for 6 unknowns: either nothing can be identified (an error saying why)
// or every joint is flagged; never a stiffness reported as identified.
void expect_nothing_identified(const RobotModel& m, const std::vector<StiffnessMeasurement>& data) {
  try {
    const StiffnessEstimate est = identify_stiffness(m, data);
    EXPECT_EQ(est.unidentifiable_joints.size(), 6U) << ::testing::PrintToString(est.warnings);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no joint can be identified"), std::string::npos) << e.what();
  }
}

TEST(UnderdeterminedIdentification, OneRowIdentifiesNothing) {
  const RobotModel m = builtin_irb6700();
  expect_nothing_identified(m, exact_measurements(m, 1));
}

TEST(UnderdeterminedIdentification, OneRowWithThreeJointsHeldStillIdentifiesNothingWithoutResidual) {
  // 3 equations for the 3 free joints: a solution, but no residual degree of freedom, so no
  // standard error; those joints are flagged rather than reported.
  const RobotModel m = builtin_irb6700();
  IdentificationOptions o;
  o.fixed_stiffness_nm_per_rad = {std::nullopt, std::nullopt, std::nullopt, 6e5, 5e5, 3e5};
  try {
    const StiffnessEstimate est = identify_stiffness(m, exact_measurements(m, 1), o);
    for (int j : {1, 2, 3}) {
      EXPECT_NE(std::find(est.unidentifiable_joints.begin(), est.unidentifiable_joints.end(), j),
                est.unidentifiable_joints.end())
          << "joint " << j << ": " << ::testing::PrintToString(est.warnings);
    }
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no joint can be identified"), std::string::npos) << e.what();
  }
}

TEST(UnderdeterminedIdentification, EnoughRowsIdentifyAgain) {
  const RobotModel m = builtin_irb6700();
  const StiffnessEstimate est = identify_stiffness(m, exact_measurements(m, 12));
  // Not every joint need be excited by these few wrenches, but the flags are no longer all of them.
  EXPECT_LT(est.unidentifiable_joints.size(), 6U) << ::testing::PrintToString(est.warnings);
}

TEST(UnderdeterminedIdentification, NanThresholdIsRefused) {
  const RobotModel m = builtin_irb6700();
  IdentificationOptions o;
  o.max_relative_std_error = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)identify_stiffness(m, exact_measurements(m, 12), o), InputError);
}

}  // namespace
}  // namespace deflex
