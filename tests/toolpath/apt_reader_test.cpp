// APT/CL data read against points worked out by hand, in the forms CAM systems write (ISO 4343 as
// Fusion's APT post, NX's CLSF with TLDATA and 11-value CIRCLE records, CATIA's blanks).
#include <cmath>

#include <gtest/gtest.h>

#include "support/error_of.hpp"
#include "toolpath/toolpath_test_util.hpp"

namespace deflex::test {
namespace {

constexpr double kAptExact = 1e-12;

TEST(AptReader, IsoRecordsGiveTheHandComputedPoints) {
  const std::string cl =
      "$$ a test part\n"            // 1
      "PARTNO TEST PART 1\n"        // 2
      "UNITS/MM\n"                  // 3
      "CUTTER/10.0,0.5\n"           // 4
      "LOADTL/1\n"                  // 5
      "SPINDL/RPM,15000,CLW\n"      // 6
      "RAPID\n"                     // 7
      "GOTO/0,0,50\n"               // 8
      "FEDRAT/MMPM,600\n"           // 9
      "GOTO/0,0,0\n"                // 10
      "GOTO/20,0,0 $$ along x\n"    // 11
      "CIRCLE/20,10,0,0,0,1,10\n"   // 12
      "GOTO/30,10,0\n"              // 13
      "MULTAX/ON\n"                 // 14
      "GOTO/30,20,0,0.0,0.6,0.8\n"  // 15
      "SPINDL/OFF\n"                // 16
      "FINI\n";                     // 17
  ToolpathSummary s;
  const auto p = apt_points(cl, {}, &s);
  // 1 rapid, 2 lines, the quarter arc of r = 10 mm in 18 chords (see the G-code arc test), 1 line.
  ASSERT_EQ(p.size(), 22u);
  EXPECT_EQ(p[0].motion, MotionKind::kRapid);
  EXPECT_EQ(p[0].feed_m_s, 0.0);
  EXPECT_EQ(p[0].line, 8u);
  EXPECT_NEAR((p[0].position_m - mm(0, 0, 50)).norm(), 0.0, kAptExact);
  EXPECT_EQ(p[1].motion, MotionKind::kLinear);  // RAPID was for one GOTO only
  EXPECT_NEAR(p[1].feed_m_s, 0.01, kAptExact);  // 600 mm/min
  EXPECT_NEAR((p[2].position_m - mm(20, 0, 0)).norm(), 0.0, kAptExact);
  for (std::size_t k = 3; k <= 20; ++k) {
    EXPECT_NEAR((p[k].position_m - mm(20, 10, 0)).norm(), 0.010, 1e-15) << k;
    EXPECT_EQ(p[k].motion, MotionKind::kArcCcw);
    EXPECT_EQ(p[k].line, 13u);
    // Counter-clockwise about +z from -90 degrees: at -90 + 5k degrees.
    const Vector3 d = p[k].position_m - mm(20, 10, 0);
    EXPECT_NEAR(std::atan2(d.y(), d.x()), -kPi / 2 + kPi / 2 * static_cast<double>(k - 2) / 18.0, 1e-12) << k;
  }
  EXPECT_EQ(p[20].position_m, mm(30, 10, 0));
  EXPECT_NEAR((p[21].tool_axis - Vector3(0, 0.6, 0.8)).norm(), 0.0, 1e-15);
  for (const auto& q : p) {
    EXPECT_EQ(q.tool, 1);
    EXPECT_EQ(q.spindle, SpindleState::kClockwise);
    EXPECT_EQ(q.spindle_rpm, 15000.0);
  }
  ASSERT_TRUE(s.cutter.has_value());
  EXPECT_NEAR(s.cutter->diameter_m, 0.010, kAptExact);
  EXPECT_NEAR(s.cutter->corner_radius_m, 0.0005, kAptExact);
  ASSERT_EQ(s.tools.size(), 1u);
  ASSERT_TRUE(s.tools[0].cutter.has_value());
  EXPECT_EQ(s.tools[0].cutter->line, 4u);
  EXPECT_EQ(s.format, ToolpathFormat::kApt);
  EXPECT_TRUE(s.multi_axis);
  EXPECT_EQ(s.arcs, 1u);
}

TEST(AptReader, NxClsfFormReads) {
  // NX writes TOOL PATH/ headers, TLDATA, PAINT records, LOAD/TOOL and CIRCLE records with tolerances.
  const std::string cl =
      "TOOL PATH/PLANAR_MILL,TOOL,FLAT_TOOL\n"
      "TLDATA/MILL,12.0000,0.0000,50.0000,0.0000,0.0000\n"
      "MSYS/0.0000,0.0000,0.0000,1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000\n"
      "$$ centerline data\n"
      "PAINT/PATH\n"
      "PAINT/SPEED,10\n"
      "LOAD/TOOL,4,ADJUST,4\n"
      "SPINDL/RPM,8000,CLW\n"
      "PAINT/COLOR,186\n"
      "RAPID\n"
      "GOTO/40.0000,50.0000,-5.0000\n"
      "FEDRAT/MMPM,300.0000\n"
      "CIRCLE/40.0000,30.0000,-5.0000,0.0000000,0.0000000,-1.0000000,20.0000,0.0600,0.5000,12.0000,0.0000\n"
      "GOTO/60.0000,30.0000,-5.0000\n"
      "PAINT/COLOR,37\n"
      "GOTO/60.0000,30.0000,20.0000\n"
      "END-OF-PATH\n";
  ToolpathSummary s;
  const auto p = apt_points(cl, {}, &s);
  // Axis -z: counter-clockwise about -z is clockwise seen from above: from (40,50) through the right.
  ASSERT_GT(p.size(), 3u);
  for (std::size_t k = 1; k + 1 < p.size(); ++k) {
    EXPECT_NEAR((p[k].position_m - mm(40, 30, -5)).norm(), 0.020, 1e-15) << k;
    EXPECT_GT(p[k].position_m.x(), 0.040) << k;
    EXPECT_EQ(p[k].motion, MotionKind::kArcCw);
  }
  EXPECT_EQ(p.back().motion, MotionKind::kLinear);
  EXPECT_EQ(p.back().tool, 4);
  ASSERT_TRUE(s.cutter.has_value());
  EXPECT_NEAR(s.cutter->diameter_m, 0.012, kAptExact);
  ASSERT_EQ(s.tools.size(), 1u);
  EXPECT_EQ(s.tools[0].number, 4);
  EXPECT_TRUE(s.tools[0].cutter.has_value());  // TLDATA after LOAD/TOOL belongs to tool 4
}

TEST(AptReader, BlanksContinuationsFeedUnitsAndInches) {
  const std::string cl =
      "UNITS / INCHES\n"
      "SPINDL/ 2300, CCLW\n"
      "FEDRAT/ 10, IPM\n"
      "GOTO  /  1.0000 ,  2.0000 , $\n"
      "   3.0000\n"
      "FEDRAT/PERMIN,20\n"
      "GOTO/2,2,3\n"
      "FEDRAT/600,MMPM\n"
      "GOTO/3,2,3\n";
  const auto p = apt_points(cl);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_NEAR((p[0].position_m - mm(25.4, 50.8, 76.2)).norm(), 0.0, kAptExact);
  EXPECT_EQ(p[0].line, 4u);
  EXPECT_NEAR(p[0].feed_m_s, 254.0 / 60000.0, kAptExact);  // 10 in/min
  EXPECT_NEAR(p[1].feed_m_s, 508.0 / 60000.0, kAptExact);  // 20 per minute in the file's inches
  EXPECT_NEAR(p[2].feed_m_s, 0.01, kAptExact);             // 600 mm/min whatever the file's unit
  EXPECT_EQ(p[0].spindle, SpindleState::kCounterClockwise);
  EXPECT_EQ(p[0].spindle_rpm, 2300.0);
}

TEST(AptReader, ToolAxisTurnsAlongTheGreatCircleAndTlaxisSetsIt) {
  ToolpathOptions o;
  o.max_linear_step_m = 0.005;
  const auto p = apt_points(
      "TLAXIS/0,0,1\nSPINDL/1000\nFEDRAT/100\nGOTO/0,0,0\nGOTO/10,0,0,0.6,0,0.8\nTLAXIS/0,1,0\nGOTO/20,0,0\n", o);
  ASSERT_EQ(p.size(), 5u);
  EXPECT_NEAR((p[1].tool_axis - Vector3(0.6, 0, 1.8).normalized()).norm(), 0.0, 1e-12);  // the bisector
  EXPECT_NEAR((p[3].tool_axis - Vector3::UnitY()).norm(), 0.0, 1e-12);
}

TEST(AptReader, FromSetsTheStartOfAnArcWithoutAPoint) {
  const auto p = apt_points("SPINDL/1000\nFEDRAT/100\nFROM/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\n");
  ASSERT_EQ(p.size(), 18u);
  EXPECT_NEAR((p[8].position_m - mm(10 * std::cos(kPi / 4), 10 * std::sin(kPi / 4), 0)).norm(), 0.0, 1e-15);
}

}  // namespace
}  // namespace deflex::test
