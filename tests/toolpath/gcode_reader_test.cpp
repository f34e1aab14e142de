// G-code read against points worked out by hand from small programs written here: modal words,
// units, incremental moves, the 5-axis forms, and the summary.
#include <cmath>

#include <gtest/gtest.h>

#include "toolpath/toolpath_test_util.hpp"

namespace deflex::test {
namespace {

constexpr double kExact = 1e-12;

TEST(GcodeReader, ThreeAxisProgramWithModalWordsGivesTheHandComputedPoints) {
  const std::string program =
      "%\n"                                // 1
      "O1001 (POCKET TEST)\n"              // 2
      "N10 G90 G94 G17 G21 G40 G49 G80\n"  // 3
      "N20 T1 M6\n"                        // 4
      "N30 S12000 M3\n"                    // 5
      "N40 G0 G54 X10 Y20\n"               // 6: Z not known yet: no point
      "N50 G43 Z15 H1 ; approach\n"        // 7
      "N60 G1 Z-2.5 F300\n"                // 8
      "N70 X40 F1500\n"                    // 9
      "\n"                                 // 10
      "N80 Y35.5 (side)\n"                 // 11
      "N90 G0 Z15 M5\n"                    // 12
      "N100 M30\n"                         // 13
      "%\n";                               // 14
  ToolpathSummary summary;
  const auto p = gcode_points(program, {}, &summary);
  ASSERT_EQ(p.size(), 5u);
  // Positions, mm.
  EXPECT_NEAR((p[0].position_m - mm(10, 20, 15)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[1].position_m - mm(10, 20, -2.5)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[2].position_m - mm(40, 20, -2.5)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[3].position_m - mm(40, 35.5, -2.5)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[4].position_m - mm(40, 35.5, 15)).norm(), 0.0, kExact);
  // Kinds, lines, segments.
  const MotionKind kinds[] = {MotionKind::kRapid, MotionKind::kLinear, MotionKind::kLinear, MotionKind::kLinear,
                              MotionKind::kRapid};
  const std::size_t lines[] = {7, 8, 9, 11, 12};
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(p[i].motion, kinds[i]) << i;
    EXPECT_EQ(p[i].line, lines[i]) << i;
    EXPECT_EQ(p[i].segment, i) << i;
    EXPECT_EQ(p[i].tool, 1) << i;
    EXPECT_EQ(p[i].spindle_rpm, 12000.0) << i;
    EXPECT_EQ(p[i].tool_axis, Vector3::UnitZ()) << i;
  }
  // Feed: 0 on rapids; 300 mm/min = 0.005 m/s; 1500 mm/min = 0.025 m/s, carried to line 11.
  EXPECT_EQ(p[0].feed_m_s, 0.0);
  EXPECT_NEAR(p[1].feed_m_s, 0.005, kExact);
  EXPECT_NEAR(p[2].feed_m_s, 0.025, kExact);
  EXPECT_NEAR(p[3].feed_m_s, 0.025, kExact);
  EXPECT_EQ(p[4].feed_m_s, 0.0);
  EXPECT_EQ(p[3].spindle, SpindleState::kClockwise);
  EXPECT_EQ(p[4].spindle, SpindleState::kOff);  // M5 acts before the block's motion
  EXPECT_EQ(summary.rapids_before_position_known, 1u);
  EXPECT_EQ(summary.points, 5u);
  EXPECT_EQ(summary.motion_blocks, 5u);
  EXPECT_EQ(summary.lines, 14u);
  EXPECT_EQ(summary.units, LengthUnit::kMillimetre);
  EXPECT_FALSE(summary.multi_axis);
  ASSERT_EQ(summary.tools.size(), 1u);
  EXPECT_EQ(summary.tools[0].number, 1);
  EXPECT_EQ(summary.tools[0].line, 4u);
  EXPECT_FALSE(summary.cutter.has_value());
}

TEST(GcodeReader, InchesAndIncrementalMovesConvertToMetres) {
  const std::string program =
      "G20 G90 G17\n"
      "S8000 M4\n"
      "G0 X1 Y2 Z0.5\n"    // (25.4, 50.8, 12.7) mm
      "G91 G1 X0.5 F20\n"  // +12.7 mm in x; 20 in/min = 508 mm/min
      "Y-1\n"              // -25.4 mm in y
      "G21 X10\n"          // now mm: +10 mm in x; the feed stays 508 mm/min
      "G90 X0 Y0 Z0\n";
  ToolpathSummary summary;
  const auto p = gcode_points(program, {}, &summary);
  ASSERT_EQ(p.size(), 5u);
  EXPECT_NEAR((p[0].position_m - mm(25.4, 50.8, 12.7)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[1].position_m - mm(38.1, 50.8, 12.7)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[2].position_m - mm(38.1, 25.4, 12.7)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[3].position_m - mm(48.1, 25.4, 12.7)).norm(), 0.0, kExact);
  EXPECT_NEAR(p[4].position_m.norm(), 0.0, kExact);
  EXPECT_NEAR(p[1].feed_m_s, 508.0 / 60000.0, kExact);
  EXPECT_NEAR(p[3].feed_m_s, 508.0 / 60000.0, kExact);
  EXPECT_EQ(p[1].spindle, SpindleState::kCounterClockwise);
  EXPECT_EQ(summary.units, LengthUnit::kInch);
  EXPECT_TRUE(summary.units_changed);
}

TEST(GcodeReader, CompactBlanksAndLowerCaseWordsReadAlike) {
  const std::string a = "G21G90G17\nS1000M3\nG0X1Y2Z3\nG1X4.5Y-.5F600\n";
  const std::string b = "g21 g90 g17\ns1000 m3\ng00 x 1 y 2 z 3\r\ng01 x +4.50 y -0.5 f 600\r\n";
  const auto pa = gcode_points(a);
  const auto pb = gcode_points(b);
  ASSERT_EQ(pa.size(), 2u);
  ASSERT_EQ(pb.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(pa[i].position_m, pb[i].position_m);
    EXPECT_EQ(pa[i].feed_m_s, pb[i].feed_m_s);
  }
  EXPECT_NEAR((pa[1].position_m - mm(4.5, -0.5, 3)).norm(), 0.0, kExact);
}

TEST(GcodeReader, ByteOrderMarkAndEveryLineEndingRead) {
  const auto p = gcode_points("\xEF\xBB\xBFG0 X1 Y2 Z3\rG0 X2\r\nG0 X3\nG0 X4");
  ASSERT_EQ(p.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(p[i].line, i + 1);
    EXPECT_NEAR(p[i].position_m.x(), static_cast<double>(i + 1) * 1e-3, kExact);
  }
}

TEST(GcodeReader, ToolChangeNeedsM6AndToolsAreListedInOrder) {
  const auto p = gcode_points("T3\nS100 M3\nG0 X0 Y0 Z0\nM6\nG0 X1\nT7 M6\nG0 X2\nT3 M6\nG0 X3\n", {}, nullptr);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p[0].tool, 0);  // T3 selected, not yet changed
  EXPECT_EQ(p[1].tool, 3);
  EXPECT_EQ(p[2].tool, 7);
  EXPECT_EQ(p[3].tool, 3);
  ToolpathSummary s;
  (void)gcode_points("T3\nT7\nT3\nG0 X0 Y0 Z0\n", {}, &s);
  ASSERT_EQ(s.tools.size(), 2u);
  EXPECT_EQ(s.tools[0].number, 3);
  EXPECT_EQ(s.tools[1].number, 7);
}

TEST(GcodeReader, SiemensOrientationVectorsUnderTraori) {
  // From +z to (0, 0.6, 0.8) in two steps: the middle axis bisects them, (0, 0.6, 1.8) normalised.
  ToolpathOptions o;
  o.max_linear_step_m = 0.005;
  ToolpathSummary s;
  const auto p = gcode_points(
      "G17 G90 G94\nTRAORI\nORIWKS\nORIVECT\nS10000 M3\nG0 X0 Y0 Z10\nG1 X10 Y0 Z10 A3=0 B3=0.6 C3=0.8 F1000\n"
      "TRAFOOF\n",
      o, &s);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_NEAR((p[1].position_m - mm(5, 0, 10)).norm(), 0.0, kExact);
  EXPECT_NEAR((p[1].tool_axis - Vector3(0, 0.6, 1.8).normalized()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((p[2].tool_axis - Vector3(0, 0.6, 0.8)).norm(), 0.0, 1e-15);
  EXPECT_EQ(p[1].segment, p[2].segment);
  EXPECT_TRUE(s.multi_axis);
}

TEST(GcodeReader, FanucToolVectorByIjkUnderG43Point5) {
  const auto p = gcode_points("S5000 M3\nG43.5 H1\nG0 X0 Y0 Z5 I0 J-0.6 K0.8\nG1 X2 F100\nG49\n");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR((p[0].tool_axis - Vector3(0, -0.6, 0.8)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((p[1].tool_axis - Vector3(0, -0.6, 0.8)).norm(), 0.0, 1e-15);  // carried
}

TEST(GcodeReader, RotaryAnglesUnderBothConventions) {
  // Head-head: axis = Rz(C) Ry(B) Rx(A) z; Rx(A) z = (0, -sin A, cos A), Ry(B) z = (sin B, 0, cos B).
  // Table-table: the part turns instead: Rx(-A) z = (0, sin A, cos A), Ry(-B) z = (-sin B, 0, cos B).
  const double s30 = 0.5, c30 = std::sqrt(3.0) / 2.0, r = std::sqrt(0.5);
  const std::string program = "S5000 M3\nG0 X0 Y0 Z0 A30\nG0 B30 A0\nG0 A30 B0 C45\n";
  ToolpathOptions head;
  const auto h = gcode_points(program, head);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_NEAR((h[0].tool_axis - Vector3(0, -s30, c30)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((h[1].tool_axis - Vector3(s30, 0, c30)).norm(), 0.0, 1e-15);
  // Rz(45) applied to (0, -0.5, c30): (0.5 sin45, -0.5 cos45, c30).
  EXPECT_NEAR((h[2].tool_axis - Vector3(s30 * r, -s30 * r, c30)).norm(), 0.0, 1e-15);
  ToolpathOptions table;
  table.rotary = RotaryConvention::kTableTable;
  const auto t = gcode_points(program, table);
  EXPECT_NEAR((t[0].tool_axis - Vector3(0, s30, c30)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((t[1].tool_axis - Vector3(-s30, 0, c30)).norm(), 0.0, 1e-15);
  // Rz(-45) applied to (0, 0.5, c30): (0.5 sin45, 0.5 cos45, c30).
  EXPECT_NEAR((t[2].tool_axis - Vector3(s30 * r, s30 * r, c30)).norm(), 0.0, 1e-15);
}

TEST(GcodeReader, RotaryAnglesInterpolateAsTheAxesMove) {
  // A from 0 to 60 degrees in two steps: the middle point is at A = 30 (head-head: (0, -sin 30, cos 30)).
  ToolpathOptions o;
  o.max_linear_step_m = 0.001;
  const auto p = gcode_points("S5000 M3\nF500\nG0 X0 Y0 Z0\nG1 X2 A60\n", o);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_NEAR((p[1].tool_axis - Vector3(0, -0.5, std::sqrt(3.0) / 2.0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((p[2].tool_axis - Vector3(0, -std::sqrt(3.0) / 2.0, 0.5)).norm(), 0.0, 1e-15);
}

TEST(GcodeReader, LongMovesSplitIntoEqualStepsWhenAsked) {
  ToolpathOptions o;
  o.max_linear_step_m = 0.004;  // 10 mm in steps of at most 4 mm: 3 steps of 10/3 mm
  const auto p = gcode_points("S5000 M3\nG0 X0 Y0 Z0\nG1 X10 F600\nG0 X30\n", o);
  ASSERT_EQ(p.size(), 5u);
  EXPECT_NEAR(p[1].position_m.x(), 10.0 / 3.0 * 1e-3, kExact);
  EXPECT_NEAR(p[2].position_m.x(), 20.0 / 3.0 * 1e-3, kExact);
  EXPECT_EQ(p[3].position_m.x(), 0.01);
  EXPECT_EQ(p[4].position_m.x(), 0.03);  // a rapid is not split
  EXPECT_EQ(p[1].segment, 1u);
  EXPECT_EQ(p[3].segment, 1u);
  EXPECT_EQ(p[4].segment, 2u);
}

TEST(GcodeReader, DwellStopsAndCoolantGiveNoPoint) {
  const auto p = gcode_points("S100 M3 M8\nG0 X0 Y0 Z0\nG4 P0.5\nG4 X2\nM0\nM1\nM9\nG1 X1 F10\n");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[1].position_m.x(), 0.001);
}

TEST(GcodeReader, SiemensDialectReadsG70AndG71) {
  ToolpathOptions o;
  o.dialect = GcodeDialect::kSiemens;
  const auto p = gcode_points("G70\nG0 X1 Y0 Z0\nG71\nG0 X1\n", o);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR(p[0].position_m.x(), 0.0254, kExact);
  EXPECT_NEAR(p[1].position_m.x(), 0.001, kExact);
}

TEST(GcodeReader, FileExtensionsChooseTheReader) {
  EXPECT_EQ(toolpath_format_for("a/b/part.nc"), ToolpathFormat::kGcode);
  EXPECT_EQ(toolpath_format_for("PART.NC"), ToolpathFormat::kGcode);
  EXPECT_EQ(toolpath_format_for("x.gcode"), ToolpathFormat::kGcode);
  EXPECT_EQ(toolpath_format_for("x.tap"), ToolpathFormat::kGcode);
  EXPECT_EQ(toolpath_format_for("x.apt"), ToolpathFormat::kApt);
  EXPECT_EQ(toolpath_format_for("x.CLS"), ToolpathFormat::kApt);
}

}  // namespace
}  // namespace deflex::test
