// Arcs against closed forms written here: centres from I J K and from R (both signs, both senses),
// the three planes, full circles, helices, the chord count and chord error of the stated tolerance,
// and the radius tolerance at its edge.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "deflex/toolpath/detail/block_points.hpp"
#include "support/error_of.hpp"
#include "toolpath/toolpath_test_util.hpp"

namespace deflex::test {
namespace {

const std::string kStart = "G17 G21 G90 G94\nS10000 M3\nF1000\n";

/// The signed angle turned from a to b about +z.
double turn_about_z(const Vector3& a, const Vector3& b) {
  return std::atan2(a.x() * b.y() - a.y() * b.x(), a.x() * b.x() + a.y() * b.y());
}

TEST(Arcs, QuarterClockwiseByIjkHasTheClosedFormChordCount) {
  // r = 10 mm, tolerance 0.01 mm: one chord may sweep 2 acos(1 - 0.01/10) = 0.0894502 rad; 90 degrees
  // (1.5707963 rad) need ceil(17.56) = 18 chords.
  const auto p = gcode_points(kStart + "G0 X10 Y0 Z0\nG2 X0 Y-10 I-10 J0\n");
  ASSERT_EQ(p.size(), 19u);
  const Vector3 centre = mm(0, 0, 0);
  Vector3 previous = mm(10, 0, 0);
  for (std::size_t k = 1; k <= 18; ++k) {
    const Vector3 q = p[k].position_m;
    EXPECT_NEAR((q - centre).norm(), 0.010, 1e-15) << k;
    // Clockwise about +z, 5 degrees a chord: at -5k degrees.
    EXPECT_NEAR(std::atan2(q.y(), q.x()), -kPi / 2.0 * static_cast<double>(k) / 18.0, 1e-12) << k;
    // Chord error: the chord's midpoint lies r cos(step / 2) from the centre.
    const double sagitta = 0.010 - ((q + previous) / 2.0 - centre).norm();
    EXPECT_LE(sagitta, 1e-5) << k;
    EXPECT_GT(sagitta, 0.5e-5) << k;  // and not needlessly fine: 10 (1 - cos 2.5 deg) = 0.0095 mm
    EXPECT_EQ(p[k].motion, MotionKind::kArcCw);
    EXPECT_EQ(p[k].segment, 1u);
    EXPECT_EQ(p[k].line, 5u);
    previous = q;
  }
  EXPECT_EQ(p[18].position_m, mm(0, -10, 0));  // the block's own end, exactly
}

TEST(Arcs, RadiusArcsPickTheirCentreBySignAndSense) {
  // From (0,0) to (10,10) with |R| = 10 the centre is (10,0) or (0,10). Clockwise the short way
  // round goes about (10,0) (from 180 to 90 degrees); counter-clockwise the short way about (0,10).
  struct Case {
    const char* block;
    Vector3 centre;
    double sweep;  // signed, about +z
  };
  const Case cases[] = {{"G2 X10 Y10 R10", mm(10, 0, 0), -kPi / 2},
                        {"G2 X10 Y10 R-10", mm(0, 10, 0), -3 * kPi / 2},
                        {"G3 X10 Y10 R10", mm(0, 10, 0), kPi / 2},
                        {"G3 X10 Y10 R-10", mm(10, 0, 0), 3 * kPi / 2}};
  for (const Case& c : cases) {
    const auto p = gcode_points(kStart + "G0 X0 Y0 Z0\n" + c.block + "\n");
    ASSERT_GT(p.size(), 2u) << c.block;
    double turned = 0.0;
    for (std::size_t k = 1; k < p.size(); ++k) {
      EXPECT_NEAR((p[k].position_m - c.centre).norm(), 0.010, 1e-15) << c.block << " point " << k;
      turned += turn_about_z(p[k - 1].position_m - c.centre, p[k].position_m - c.centre);
    }
    EXPECT_NEAR(turned, c.sweep, 1e-12) << c.block;
    EXPECT_EQ(p.back().position_m, mm(10, 10, 0)) << c.block;
  }
}

TEST(Arcs, ZxAndYzPlanesTurnTheWayG18AndG19Say) {
  // G18: seen from +Y, Z points right and X up; G2 from X = -10 (below the centre) goes through -Z.
  // Half a turn of r = 10 mm: ceil(pi / 0.0894502) = 36 chords, the 18th at the quarter.
  const auto a = gcode_points(kStart + "G0 X0 Y0 Z0\nG18 G2 X20 Z0 I10 K0\n");
  ASSERT_EQ(a.size(), 37u);
  const std::size_t half = 18;
  EXPECT_NEAR((a[half].position_m - mm(10, 0, -10)).norm(), 0.0, 1e-15);
  for (std::size_t k = 1; k + 1 < a.size(); ++k) {
    EXPECT_LT(a[k].position_m.z(), 0.0);
    EXPECT_EQ(a[k].position_m.y(), 0.0);
  }
  // G19: seen from +X, Y points right and Z up; G3 from Y = -10 (left of the centre) goes through -Z.
  const auto b = gcode_points(kStart + "G0 X0 Y0 Z0\nG19 G3 Y20 Z0 J10 K0\n");
  ASSERT_EQ(b.size(), 37u);
  EXPECT_NEAR((b[18].position_m - mm(0, 10, -10)).norm(), 0.0, 1e-15);
  for (std::size_t k = 1; k + 1 < b.size(); ++k) {
    EXPECT_LT(b[k].position_m.z(), 0.0);
    EXPECT_EQ(b[k].position_m.x(), 0.0);
  }
}

TEST(Arcs, FullCircleByIjkAndHelix) {
  // A whole turn of r = 10 mm at 0.01 mm: ceil(2 pi / 0.0894502) = ceil(70.24) = 71 chords.
  const auto c = gcode_points(kStart + "G0 X0 Y0 Z0\nG2 I10 J0\n");
  ASSERT_EQ(c.size(), 72u);
  double turned = 0.0;
  for (std::size_t k = 1; k < c.size(); ++k) {
    EXPECT_NEAR((c[k].position_m - mm(10, 0, 0)).norm(), 0.010, 1e-15);
    turned += turn_about_z(c[k - 1].position_m - mm(10, 0, 0), c[k].position_m - mm(10, 0, 0));
  }
  EXPECT_NEAR(turned, -2 * kPi, 1e-12);
  EXPECT_EQ(c.back().position_m, mm(0, 0, 0));
  // A quarter helix down 2 mm: 18 chords, the 9th at 45 degrees and 1 mm down.
  const auto h = gcode_points(kStart + "G0 X10 Y0 Z0\nG3 X0 Y10 Z-2 I-10 J0\n");
  ASSERT_EQ(h.size(), 19u);
  const double r = 10.0 / std::sqrt(2.0);
  EXPECT_NEAR((h[9].position_m - mm(r, r, -1)).norm(), 0.0, 1e-15);
  EXPECT_EQ(h[9].motion, MotionKind::kArcCcw);
}

TEST(Arcs, RadiusToleranceAcceptsWithinAndRefusesBeyondNamingTheLineAndWord) {
  const std::string start = kStart + "G0 X10 Y0 Z0\n";  // the arc is on line 5
  // The end 0.005 mm off the circle: within 0.01 mm; the points end exactly at the end point.
  const auto p = gcode_points(start + "G2 X0 Y-10.005 I-10 J0\n");
  EXPECT_EQ(p.back().position_m, mm(0, -10.005, 0));
  const std::string e = error_of([&] { (void)gcode_points(start + "G2 X0 Y-10.02 I-10 J0\n"); });
  EXPECT_NE(e.find("t.nc:5: word 'I-10'"), std::string::npos) << e;
  EXPECT_NE(e.find("differ by 0.0200 mm"), std::string::npos) << e;
  // R: half the chord 0.005 mm longer than R is within the tolerance, 0.015 mm is not.
  EXPECT_NO_THROW((void)gcode_points(kStart + "G0 X0 Y0 Z0\nG2 X20 Y0 R9.995\n"));
  const std::string r = error_of([&] { (void)gcode_points(kStart + "G0 X0 Y0 Z0\nG2 X20 Y0 R9.985\n"); });
  EXPECT_NE(r.find("t.nc:5: word 'R9.985'"), std::string::npos) << r;
  EXPECT_NE(r.find("half the chord is 10.0000 mm, longer than R by 0.0150 mm"), std::string::npos) << r;
  // A tighter tolerance refuses what the default accepted.
  ToolpathOptions tight;
  tight.arc_radius_tolerance_m = 1e-6;
  EXPECT_NE(error_of([&] { (void)gcode_points(start + "G2 X0 Y-10.005 I-10 J0\n", tight); }).find("differ by"),
            std::string::npos);
}

TEST(Arcs, ChordCountIsTheFewestThatKeepsTheSagittaWithinTolerance) {
  // For random radii, sweeps and tolerances: with n chords the sagitta r (1 - cos(sweep / 2n)) is
  // within the tolerance, and with n - 1 it is not (unless n is set by the 90-degree step).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> radius(1e-4, 0.5), sweep(1e-3, 2 * kPi), tol_exp(-7.0, -3.0);
  for (int i = 0; i < 2000; ++i) {
    detail::ArcGeometry g;
    g.radius_start_m = g.radius_end_m = radius(rng);
    g.sweep_rad = sweep(rng);
    const double tol = std::pow(10.0, tol_exp(rng));
    const double n = detail::arc_step_count(g, tol);
    const auto sagitta = [&](double chords) { return g.radius_start_m * (1.0 - std::cos(g.sweep_rad / (2 * chords))); };
    EXPECT_LE(sagitta(n), tol * (1 + 1e-9)) << i;
    EXPECT_LE(g.sweep_rad / n, kPi / 2 + 1e-12) << i;
    if (n > 1 && g.sweep_rad / (n - 1) <= kPi / 2) {
      EXPECT_GT(sagitta(n - 1), tol) << i;
    }
  }
}

TEST(Arcs, AbsoluteArcCentresUnderG90Point1) {
  const auto p = gcode_points(kStart + "G90.1\nG0 X10 Y0 Z0\nG2 X0 Y-10 I0 J0\nG91.1\nG3 X10 Y0 I0 J10\n");
  ASSERT_EQ(p.size(), 37u);
  for (std::size_t k = 1; k < p.size(); ++k) {
    EXPECT_NEAR(p[k].position_m.norm(), 0.010, 1e-15) << k;
  }
}

}  // namespace
}  // namespace deflex::test
