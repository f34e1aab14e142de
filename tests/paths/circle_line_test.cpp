// Circle and line sampling against closed-form geometry written here, and their input errors.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/line_path.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

const Eigen::Quaterniond kDown(0.0, 0.0, 1.0, 0.0);

TEST(CirclePath, PaperCircleHas81PointsFourPointFiveDegreesApartAndCloses) {
  CirclePath c;
  c.centre_m = Vector3(1.5, 0.0, 1.0);
  c.radius_m = 0.1;
  const auto poses = sample_circle(c, kDown);
  ASSERT_EQ(poses.size(), 81u);
  // Default start: centre + r * x; CCW about +z means the second point has positive y.
  EXPECT_NEAR((poses[0].translation() - Vector3(1.6, 0.0, 1.0)).norm(), 0.0, 1e-15);
  EXPECT_GT(poses[1].translation().y(), 0.0);
  EXPECT_EQ(poses.back().translation(), poses.front().translation());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Vector3 d = poses[i].translation() - c.centre_m;
    EXPECT_NEAR(d.norm(), 0.1, 1e-15);
    EXPECT_NEAR(d.z(), 0.0, 1e-15);
    // Angle of point i measured here with atan2, in the CCW sense: 4.5 deg * i (mod 360).
    double a = std::atan2(d.y(), d.x());
    if (a < -1e-12) {
      a += 2 * kPi;
    }
    const double expected = deg_to_rad(4.5 * static_cast<double>(i % 80));
    EXPECT_NEAR(a, expected, 1e-12) << "point " << i;
    EXPECT_TRUE(poses[i].linear().isApprox(kDown.toRotationMatrix(), 1e-15));
  }
}

TEST(CirclePath, ClockwiseStartAngleAndTiltedPlane) {
  CirclePath c;
  c.centre_m = Vector3(1.0, 0.2, 0.8);
  c.radius_m = 0.05;
  c.normal = Vector3(0.0, 1.0, 1.0);  // plane tilted 45 deg about x; not unit on purpose
  c.start_angle_rad = deg_to_rad(90.0);
  c.clockwise = true;
  c.points = 13;
  const auto poses = sample_circle(c, kDown);
  const Vector3 n = Vector3(0, 1, 1).normalized();
  // Start direction u = x (x is already in the plane), v = n x u; start at 90 deg -> along v.
  const Vector3 v = n.cross(Vector3::UnitX());
  EXPECT_NEAR((poses[0].translation() - (c.centre_m + 0.05 * v)).norm(), 0.0, 1e-15);
  for (std::size_t i = 0; i + 1 < poses.size(); ++i) {
    const Vector3 a = poses[i].translation() - c.centre_m;
    const Vector3 b = poses[i + 1].translation() - c.centre_m;
    EXPECT_NEAR(a.dot(n), 0.0, 1e-15);
    // Clockwise: each step rotates by -30 deg about n.
    const double signed_angle = std::atan2(a.cross(b).dot(n), a.dot(b));
    EXPECT_NEAR(signed_angle, deg_to_rad(-30.0), 1e-12);
  }
}

TEST(CirclePath, RejectsBadInput) {
  CirclePath c;
  c.radius_m = 0.0;
  EXPECT_THROW((void)sample_circle(c, kDown), InputError);
  c.radius_m = std::nan("");
  EXPECT_THROW((void)sample_circle(c, kDown), InputError);
  c.radius_m = 0.1;
  c.points = 2;
  EXPECT_THROW((void)sample_circle(c, kDown), InputError);
  c.points = 10;
  c.normal = Vector3::Zero();
  EXPECT_THROW((void)sample_circle(c, kDown), InputError);
  c.normal = Vector3::UnitX();  // the default start reference is x: parallel
  EXPECT_THROW((void)sample_circle(c, kDown), InputError);
  c.normal = Vector3::UnitZ();
  EXPECT_THROW((void)sample_circle(c, Eigen::Quaterniond(0.0, 0.0, 1.1, 0.0)), InputError);
}

TEST(LinePath, EndsAndEvenSpacing) {
  LinePath l;
  l.start_m = Vector3(1.4, -0.1, 1.0);
  l.end_m = Vector3(1.6, 0.1, 0.9);
  l.points = 5;
  const auto poses = sample_line(l, kDown);
  ASSERT_EQ(poses.size(), 5u);
  EXPECT_EQ(poses.front().translation(), l.start_m);
  EXPECT_NEAR((poses.back().translation() - l.end_m).norm(), 0.0, 1e-15);
  EXPECT_NEAR((poses[2].translation() - Vector3(1.5, 0.0, 0.95)).norm(), 0.0, 1e-15);
  l.points = 1;
  EXPECT_THROW((void)sample_line(l, kDown), InputError);
  l.points = 3;
  l.end_m = l.start_m;
  EXPECT_THROW((void)sample_line(l, kDown), InputError);
}

TEST(PathSpec, CircleKeysWithUnitsAndDefaults) {
  const CirclePath d = parse_circle_spec("");
  EXPECT_EQ(d.centre_m, Vector3(1.5, 0.0, 1.0));
  EXPECT_DOUBLE_EQ(d.radius_m, 0.1);
  EXPECT_EQ(d.points, 81);
  const CirclePath c =
      parse_circle_spec("centre_mm=1200;100;900, radius_mm=50,normal=0;0;-1,start_deg=30,direction=cw,points=41");
  EXPECT_NEAR((c.centre_m - Vector3(1.2, 0.1, 0.9)).norm(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(c.radius_m, 0.05);
  EXPECT_EQ(c.normal, Vector3(0, 0, -1));
  EXPECT_NEAR(c.start_angle_rad, deg_to_rad(30.0), 1e-15);
  EXPECT_TRUE(c.clockwise);
  EXPECT_EQ(c.points, 41);
  const LinePath l = parse_line_spec("start_mm=1400;0;1000,end_mm=1600;0;1000,points=11");
  EXPECT_NEAR((l.end_m - Vector3(1.6, 0, 1.0)).norm(), 0.0, 1e-15);
  EXPECT_EQ(l.points, 11);
}

TEST(PathSpec, ErrorsNameTheKey) {
  const auto message = [](const std::string& spec) {
    try {
      (void)parse_circle_spec(spec);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("radius=100").find("unknown key 'radius'"), std::string::npos);
  EXPECT_NE(message("radius_mm=abc").find("'abc' is not a number"), std::string::npos);
  EXPECT_NE(message("centre_mm=1;2").find("key 'centre_mm': expected 3"), std::string::npos);
  EXPECT_NE(message("points=80.5").find("key 'points'"), std::string::npos);
  EXPECT_NE(message("direction=left").find("key 'direction'"), std::string::npos);
  EXPECT_NE(message("radius_mm=-5").find("key 'radius_mm'"), std::string::npos);
  EXPECT_NE(message("points=3,points=4").find("given twice"), std::string::npos);
  EXPECT_THROW((void)parse_line_spec("start_mm=1;2;3"), InputError);
}

}  // namespace
}  // namespace deflex
