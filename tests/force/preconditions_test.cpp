// Broken preconditions of the force models refused in every build type (the tests run in Release in
// CI): an LDBB pivot placed for a circle whose centre or radius is not finite, and an LDBB wrench at a
// TCP position that is not finite. Before, the pivot came back NaN (the error surfaced later, if at
// all, as "pivot position is not finite" of a pivot the caller never gave), and the wrench was
// refused as a TCP "nan mm from the pivot".
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/force/force_spec.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/force/tool_wrench_model.hpp"
#include "deflex/paths/circle_path.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

TEST(ForcePreconditions, APivotForACircleWithoutAFiniteCentreOrRadiusIsRefused) {
  CirclePath circle;
  circle.centre_m = Vector3(1.5, 0.0, 1.0);
  circle.radius_m = 0.1;
  ASSERT_TRUE(ldbb_pivot_for_circle(circle, deg_to_rad(45.0)).allFinite());

  CirclePath no_centre = circle;
  no_centre.centre_m.z() = kNaN;
  std::string error = test::error_of([&] { (void)ldbb_pivot_for_circle(no_centre, deg_to_rad(45.0)); });
  EXPECT_NE(error.find("centre"), std::string::npos) << error;

  for (const double radius : {kNaN, std::numeric_limits<double>::infinity(), 0.0, -0.1}) {
    CirclePath bad = circle;
    bad.radius_m = radius;
    error = test::error_of([&] { (void)ldbb_pivot_for_circle(bad, deg_to_rad(45.0)); });
    EXPECT_NE(error.find("radius"), std::string::npos) << radius << ": " << error;
  }
}

TEST(ForcePreconditions, AnLdbbWrenchAtANonFiniteTcpPositionNamesThePosition) {
  const LdbbForceModel ldbb(Vector3(1.5, 0.0, 0.9), 400.0, true);
  Pose tcp = Pose::Identity();
  tcp.translation() = Vector3(1.6, kNaN, 1.0);
  const std::string error = test::error_of([&] { (void)ldbb.wrench_at(7, tcp); });
  EXPECT_NE(error.find("path point 7"), std::string::npos) << error;
  EXPECT_NE(error.find("TCP position is not finite"), std::string::npos) << error;
  Wrench w;
  EXPECT_FALSE(ldbb.wrench_at_pose(tcp, w));
}

TEST(ForcePreconditions, AToolWrenchAtANonFiniteOrientationIsRefused) {
  // Before: the tool's wrench rotated by a NaN matrix came back NaN, without an error.
  Wrench tool = Wrench::Zero();
  tool[2] = -150.0;
  const ToolWrenchModel model(tool);
  Pose tcp = Pose::Identity();
  tcp.linear()(0, 2) = kNaN;
  const std::string error = test::error_of([&] { (void)model.wrench_at(0, tcp); });
  EXPECT_NE(error.find("orientation is not finite"), std::string::npos) << error;
  // A finite orientation: the wrench turned with the tool (its z along -z of the base: +150 N along z).
  Pose down = Pose::Identity();
  down.linear() = Eigen::Quaterniond(0.0, 0.0, 1.0, 0.0).toRotationMatrix();
  EXPECT_NEAR(model.wrench_at(0, down)[2], 150.0, 1e-12);
}

}  // namespace
}  // namespace deflex
