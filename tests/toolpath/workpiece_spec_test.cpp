// The workpiece placement spec against poses written here, and its refusals.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/workpiece_spec.hpp"
#include "support/error_of.hpp"

namespace deflex::test {
namespace {

TEST(WorkpieceSpec, PositionInMmAndAUnitQuaternion) {
  // A quarter turn about z: qw = qz = sqrt(1/2).
  const double h = std::sqrt(0.5);
  const Pose p = parse_workpiece_spec("x_mm=2000, y_mm=-150.5, z_mm=750, qw=" + std::to_string(h) +
                                      ",qx=0,qy=0,qz=" + std::to_string(h));
  EXPECT_NEAR((p.translation() - Vector3(2.0, -0.1505, 0.75)).norm(), 0.0, 1e-15);
  // The workpiece's x axis along the base's y.
  EXPECT_NEAR((p.linear() * Vector3::UnitX() - Vector3::UnitY()).norm(), 0.0, 1e-6);
  EXPECT_NEAR((p.linear().transpose() * p.linear() - Matrix3::Identity()).norm(), 0.0, 1e-15);
}

TEST(WorkpieceSpec, NoQuaternionMeansTheBaseAxes) {
  const Pose p = parse_workpiece_spec("x_mm=1800,y_mm=0,z_mm=500");
  EXPECT_EQ(p.linear(), Matrix3::Identity());
  EXPECT_NEAR(p.translation().x(), 1.8, 1e-15);
}

TEST(WorkpieceSpec, QuaternionSlightlyOffUnitIsNormalisedFartherIsRefused) {
  // 0.7071 written with four decimals: norm 0.99999 (within 1e-3).
  const Pose p = parse_workpiece_spec("x_mm=0,y_mm=0,z_mm=0,qw=0.7071,qx=0.7071,qy=0,qz=0");
  EXPECT_NEAR((p.linear().transpose() * p.linear() - Matrix3::Identity()).norm(), 0.0, 1e-15);
  const std::string e = error_of([] { (void)parse_workpiece_spec("x_mm=0,y_mm=0,z_mm=0,qw=0.9,qx=0,qy=0,qz=0"); });
  EXPECT_NE(e.find("has norm 0.900000, not 1"), std::string::npos) << e;
  EXPECT_NE(e.find("spec 'x_mm=0,y_mm=0,z_mm=0,qw=0.9"), std::string::npos) << e;
}

TEST(WorkpieceSpec, RefusalsNameTheKey) {
  struct Case {
    const char* spec;
    const char* expect;
  };
  const Case cases[] = {
      {"x_mm=0,y_mm=0", "key 'z_mm' (the workpiece origin in the robot's base frame, mm) is required"},
      {"x_mm=0,y_mm=0,z_mm=0,w=1", "unknown key 'w'"},
      {"x_mm=0,x_mm=1,y_mm=0,z_mm=0", "key 'x_mm' given twice"},
      {"x_mm=nan,y_mm=0,z_mm=0", "key 'x_mm': 'nan' is not a finite number"},
      {"x_mm=1e6,y_mm=0,z_mm=0", "key 'x_mm': 1e+06 mm is outside"},
      {"x_mm=0,y_mm=0,z_mm=0,qw=1", "give all four of qw, qx, qy, qz"},
      {"x_mm=0,y_mm=0,z_mm=0,qw=0,qx=0,qy=0,qz=0", "has norm 0.000000"},
      {"x_mm=0;1,y_mm=0,z_mm=0", "key 'x_mm': expected 1 ';'-separated numbers, got 2"},
      {"x_mm 0", "'x_mm 0' is not key=value"},
  };
  for (const Case& c : cases) {
    std::string message = "no error";
    try {
      (void)parse_workpiece_spec(c.spec);
    } catch (const InputError& e) {
      message = e.what();
    }
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.spec << ": " << message;
  }
}

}  // namespace
}  // namespace deflex::test
