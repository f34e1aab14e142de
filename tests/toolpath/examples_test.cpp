// The shipped machining examples read cleanly and are the parts their comments describe: the pocket's
// tool centre never comes nearer than the cutter's radius to the pocket's walls, and the swarf pass
// leans its tool as the wall leans.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/toolpath/toolpath_reader.hpp"

namespace deflex::test {
namespace {

const std::string kDir = std::string(DEFLEX_SOURCE_DIR) + "/examples/machining/";

/// Distance by which a point lies outside the rectangle |x| <= a, |y| <= b with corners of radius r (mm).
double outside_rounded_rectangle(double x, double y, double a, double b, double r) {
  const double dx = std::max(std::abs(x) - (a - r), 0.0), dy = std::max(std::abs(y) - (b - r), 0.0);
  return std::hypot(dx, dy) - r;
}

TEST(MachiningExamples, PocketStaysAtTheCuttersRadiusFromItsWalls) {
  const Toolpath t = read_toolpath(kDir + "pocket_contour.nc");
  EXPECT_EQ(t.summary.units, LengthUnit::kMillimetre);
  EXPECT_FALSE(t.summary.multi_axis);
  EXPECT_GT(t.summary.arcs, 20u);
  std::size_t pocket_points = 0;
  bool contour = false;  // from the move out to x = -65 mm on
  for (const ToolpathPoint& p : t.points) {
    const Vector3 q = p.position_m * 1e3;
    contour = contour || q.x() < -60.0;
    if (p.motion != MotionKind::kRapid) {
      EXPECT_GT(p.feed_m_s, 0.0);
      EXPECT_EQ(p.spindle, SpindleState::kClockwise);
      EXPECT_EQ(p.spindle_rpm, 15000.0);
    }
    // Below the top, inside the pocket's outline (60 x 40, corners 8): the tool's centre keeps 5 mm
    // (its radius) from the walls, i.e. inside 50 x 30 with corners 3.
    if (!contour && q.z() < 0.0) {
      ++pocket_points;
      EXPECT_LE(outside_rounded_rectangle(q.x(), q.y(), 25.0, 15.0, 3.0), 1e-9) << p.line;
      EXPECT_GE(q.z(), -5.0 - 1e-9) << p.line;
    }
  }
  EXPECT_GT(pocket_points, 200u);
}

TEST(MachiningExamples, SwarfPassLeansItsToolWithTheWall) {
  const Toolpath t = read_toolpath(kDir + "swarf_wall.apt");
  EXPECT_TRUE(t.summary.multi_axis);
  ASSERT_TRUE(t.summary.cutter.has_value());
  EXPECT_NEAR(t.summary.cutter->diameter_m, 0.010, 1e-12);
  std::size_t on_wall = 0;
  for (const ToolpathPoint& p : t.points) {
    const double x = p.position_m.x() * 1e3;
    if (p.motion == MotionKind::kRapid || x < 0.0 || x > 60.0) continue;
    ++on_wall;
    const double lean_deg = rad_to_deg(std::atan2(p.tool_axis.y(), p.tool_axis.z()));
    EXPECT_NEAR(lean_deg, 10.0 + 10.0 * x / 60.0, 1e-3) << p.line;  // six decimals of the axis
    EXPECT_NEAR(p.tool_axis.x(), 0.0, 1e-12);
  }
  EXPECT_EQ(on_wall, 62u);  // two passes of 31 points
}

}  // namespace
}  // namespace deflex::test
