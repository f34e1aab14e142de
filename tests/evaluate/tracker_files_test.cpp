// Spatial Analyzer ASCII exports and unit-named CSV: every layout the SA export dialog offers (name
// columns, coordinate systems, uncertainties, time stamps, separators, notation), positions checked
// against the values written by hand, and each kind of bad file refused with its file and line.
#include "deflex/evaluate/tracker_files.hpp"

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

std::string file_error_of(const std::string& text, const TrackerReadOptions& o = {}) {
  try {
    parse_tracker_file(text, "session.txt", o);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SaExport, CollectionGroupTargetWithHeaderInMillimetres) {
  const TrackerFile f = parse_tracker_file(
      "// SA Version: 2023.1\n// Working Frame: Tracker\n// Units: Millimeters\n"
      "Job Circle P1 1000.5 -20.25 900\nJob Circle P2 1001.5 -21.25 901\n",
      "session.txt");
  EXPECT_EQ(f.format, "sa");
  EXPECT_EQ(f.frame, "Tracker");
  EXPECT_EQ(f.version, "2023.1");
  EXPECT_EQ(f.length_unit, "mm");
  EXPECT_EQ(f.unit_from, "header");
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_TRUE(f.has_names);
  EXPECT_FALSE(f.has_time);
  EXPECT_EQ(f.points[0].name, "Job::Circle::P1");
  EXPECT_EQ(f.points[1].line, 5);
  EXPECT_NEAR(f.points[0].p_m.x(), 1.0005, 1e-15);
  EXPECT_NEAR(f.points[0].p_m.y(), -0.02025, 1e-15);
  EXPECT_NEAR(f.points[1].p_m.z(), 0.901, 1e-15);
}

TEST(SaExport, EveryNameLayoutWithoutAHeaderNeedsOnlyTheUnit) {
  TrackerReadOptions o;
  o.length_unit = "m";
  for (const char* text :
       {"G T1 1 2 3\nG T2 4 5 6\n", "T1 1 2 3\nT2 4 5 6\n", "1 2 3\n4 5 6\n", "C,G,T1,1,2,3\nC,G,T2,4,5,6\n"}) {
    const TrackerFile f = parse_tracker_file(text, "s.txt", o);
    ASSERT_EQ(f.points.size(), 2u) << text;
    EXPECT_EQ(f.unit_from, "option");
    EXPECT_DOUBLE_EQ(f.points[1].p_m.x(), 4.0) << text;
    EXPECT_DOUBLE_EQ(f.points[1].p_m.z(), 6.0) << text;
  }
}

TEST(SaExport, InchesFeetAndCentimetres) {
  for (const auto& [unit, scale] : std::vector<std::pair<std::string, double>>{
           {"Inches", 0.0254}, {"Feet", 0.3048}, {"Centimeters", 0.01}, {"Meters", 1.0}}) {
    const TrackerFile f = parse_tracker_file("// Units: " + unit + "\nP1 10 0 -2\n", "s.txt");
    EXPECT_NEAR(f.points[0].p_m.x(), 10 * scale, 1e-15) << unit;
    EXPECT_NEAR(f.points[0].p_m.z(), -2 * scale, 1e-15) << unit;
  }
}

TEST(SaExport, CylindricalAndSphericalAgainstHandComputedPoints) {
  // r = 2 m, theta = 30 deg, z = 0.5 m -> (1.7320508, 1, 0.5).
  const TrackerFile cyl = parse_tracker_file(
      "// Units: Meters, Degrees\n// Coordinate System: Cylindrical\n// Columns: Target R Theta Z\nP1 2 30 0.5\n",
      "s.txt");
  EXPECT_EQ(cyl.coordinates, "cylindrical");
  EXPECT_NEAR(cyl.points[0].p_m.x(), std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(cyl.points[0].p_m.y(), 1.0, 1e-12);
  EXPECT_NEAR(cyl.points[0].p_m.z(), 0.5, 1e-12);
  // Spherical: r = 3 m, azimuth 90 deg, zenith angle 60 deg -> (0, 3 sin 60, 3 cos 60).
  const TrackerFile sph =
      parse_tracker_file("// Units: Meters, Degrees\n// Columns: Target R Theta Phi\nP1 3 90 60\n", "s.txt");
  EXPECT_NEAR(sph.points[0].p_m.x(), 0.0, 1e-12);
  EXPECT_NEAR(sph.points[0].p_m.y(), 3.0 * std::sqrt(3.0) / 2.0, 1e-12);
  EXPECT_NEAR(sph.points[0].p_m.z(), 1.5, 1e-12);
  // The same point as azimuth and elevation (30 deg above the XY plane), angles in radians.
  TrackerReadOptions o;
  o.columns = "target r az el";
  o.angle_unit = "rad";
  const TrackerFile ae = parse_tracker_file(
      "// Units: Meters\nP1 3 " + std::to_string(M_PI / 2) + " " + std::to_string(M_PI / 6) + "\n", "s.txt", o);
  EXPECT_NEAR(ae.points[0].p_m.y(), 3.0 * std::sqrt(3.0) / 2.0, 1e-5);
  EXPECT_NEAR(ae.points[0].p_m.z(), 1.5, 1e-5);
}

TEST(SaExport, UncertaintiesToleranceAndTimeStampsInBothForms) {
  const TrackerFile f = parse_tracker_file(
      "// Units: Millimeters\n// Columns: Target X Y Z Ux Uy Uz Time\n"
      "P1 1.0e+03 2.0E+01 3 0.01 0.01 0.02 2026/11/25 10:00:59.750\n"
      "P2 1001 20 3 0.01 0.01 0.02 2026/11/25 10:01:00.250\n",
      "s.txt");
  ASSERT_TRUE(f.has_time);
  EXPECT_NEAR(f.points[1].t_s - f.points[0].t_s, 0.5, 1e-6);
  // 2026-11-25 00:00 UTC is 1795564800 s after 1970-01-01 (`date -u -d 2026-11-25 +%s`).
  EXPECT_NEAR(f.points[0].t_s, 1795564800.0 + 10 * 3600 + 59.75, 1e-5);
  EXPECT_NEAR(f.points[0].p_m.x(), 1.0, 1e-15);
  const TrackerFile secs = parse_tracker_file(
      "// Units: Millimeters\n// Columns: Collection, Group, Target, X, Y, Z, Tol, Time\n"
      "C, G, P1, 1, 2, 3, 0.05, 12.5\nC, G, P2, 1, 2, 3, 0.05, 12.501\n",
      "s.txt");
  EXPECT_DOUBLE_EQ(secs.points[1].t_s, 12.501);
  EXPECT_EQ(secs.points[0].name, "C::G::P1");
}

TEST(SaExport, WrittenExportReadsBackToTheNanometre) {
  TrackerTrace t;
  for (int i = 0; i < 50; ++i) t.push_back({0.001 * i, Vector3(1.9 + 1e-4 * i, -0.1234567 * i, 0.9)});
  for (const bool comma : {false, true}) {
    for (const bool scientific : {false, true}) {
      const auto path = std::filesystem::temp_directory_path() / "deflex_sa_roundtrip.txt";
      SaExportOptions o;
      o.frame = "AT960 Tracker";
      o.comma = comma;
      o.scientific = scientific;
      write_sa_export(t, path.string(), o);
      TrackerReadOptions ro;
      ro.expect_frame = "AT960 Tracker";
      const TrackerFile f = read_tracker_file(path.string(), ro);
      std::filesystem::remove(path);
      ASSERT_EQ(f.points.size(), t.size());
      EXPECT_EQ(f.frame, "AT960 Tracker");
      const TrackerTrace back = timed_trace(f, "test");
      for (std::size_t i = 0; i < t.size(); ++i) {
        EXPECT_NEAR((back[i].p_m - t[i].p_m).norm(), 0.0, 1e-9);
        EXPECT_NEAR(back[i].t_s, t[i].t_s, 1e-9);
      }
    }
  }
}

TEST(TrackerFileCsv, MetresOrMillimetresNamedInTheHeader) {
  const TrackerFile m = parse_tracker_file("t_s,x_m,y_m,z_m\n0,1.5,0,2\n0.001,1.5,0,2.001\n", "run.csv");
  EXPECT_EQ(m.format, "csv");
  EXPECT_EQ(m.length_unit, "m");
  EXPECT_DOUBLE_EQ(m.points[1].p_m.z(), 2.001);
  const TrackerFile mm = parse_tracker_file("x_mm,y_mm,z_mm\n1500,0,2000\n", "run.csv");
  EXPECT_FALSE(mm.has_time);
  EXPECT_DOUBLE_EQ(mm.points[0].p_m.x(), 1.5);
}

TEST(TrackerFileErrors, EachNamesTheFileAndLine) {
  // No unit anywhere.
  EXPECT_NE(file_error_of("P1 1 2 3\n").find("names no length unit"), std::string::npos);
  EXPECT_NE(file_error_of("t_s,x,y,z\n0,1,2,3\n").find("no position columns with a unit"), std::string::npos);
  // The header and the option disagree.
  TrackerReadOptions inch;
  inch.length_unit = "in";
  EXPECT_NE(file_error_of("// Units: Millimeters\nP1 1 2 3\n", inch).find("session.txt:1: the header says mm"),
            std::string::npos);
  // Mixed coordinate types: the header says one, the columns another; or two in the header.
  EXPECT_NE(file_error_of("// Units: mm\n// Coordinate System: Cylindrical\nP1 1 2 3\n").find("mixed coordinate types"),
            std::string::npos);
  EXPECT_NE(
      file_error_of("// Units: mm\n// Cartesian\n// Spherical\nP1 1 2 3\n").find("session.txt:3: mixed coordinate"),
      std::string::npos);
  // Another working frame than expected, or none named.
  TrackerReadOptions frame;
  frame.expect_frame = "Tracker";
  EXPECT_NE(file_error_of("// Working Frame: World\n// Units: mm\nP1 1 2 3\n", frame)
                .find("session.txt:1: the working frame is 'World', not the expected 'Tracker'"),
            std::string::npos);
  EXPECT_NE(file_error_of("// Units: mm\nP1 1 2 3\n", frame).find("names no working frame"), std::string::npos);
  // A line with another layout, a bad number, an ambiguous layout, an unknown column.
  EXPECT_NE(file_error_of("// Units: mm\nP1 1 2 3\nP2 1 2\n").find("session.txt:3: 3 field(s)"), std::string::npos);
  EXPECT_NE(file_error_of("// Units: mm\nP1 1 2 3\nP2 1 nan 3\n").find("session.txt:3: field 3"), std::string::npos);
  EXPECT_NE(file_error_of("// Units: mm\n1 2 3 4\n").find("--sa-columns"), std::string::npos);
  EXPECT_NE(file_error_of("// Units: mm\n// Columns: Target X Y Q\nP1 1 2 3\n").find("unknown column 'q'"),
            std::string::npos);
  EXPECT_NE(file_error_of("// Units: mm\n").find("no points"), std::string::npos);
  EXPECT_NE(file_error_of("// Units: mm\nP1 1 2 3\n// Units: m\nP2 1 2 3\n").find("session.txt:3"), std::string::npos);
}

TEST(TrackerFileErrors, TimeBasedWorkNeedsIncreasingStamps) {
  auto timed_error = [](const std::string& text) {
    try {
      timed_trace(parse_tracker_file(text, "run.csv"), "--align-to");
    } catch (const DataError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(timed_error("x_mm,y_mm,z_mm\n1,2,3\n").find("needs time stamps"), std::string::npos);
  EXPECT_NE(timed_error("t_s,x_mm,y_mm,z_mm\n0,1,2,3\n0,1,2,3\n").find("run.csv:3: time stamp 0 s repeats line 2's"),
            std::string::npos);
  EXPECT_NE(timed_error("t_s,x_mm,y_mm,z_mm\n1,1,2,3\n0.5,1,2,3\n").find("run.csv:3: time stamp 0.5 s goes back"),
            std::string::npos);
}

}  // namespace
}  // namespace deflex
