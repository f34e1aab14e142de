// Spatial Analyzer ASCII exports and unit-named CSV: every layout the SA export dialog offers (name
// columns, coordinate systems, uncertainties, time stamps, separators, notation), positions checked
// against the values written by hand, and each kind of bad file refused with its file and line.
#include "deflex/evaluate/tracker_files.hpp"

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/model/tracker_trace.hpp"
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
  // An SA export is read with its points in any order (nests sorted by name); time-based work refuses
  // a stamp that goes back.
  EXPECT_NE(timed_error("// Units: mm\n// Columns: Target X Y Z Time\nP1 1 2 3 1\nP2 1 2 3 0.5\n")
                .find("run.csv:4: time stamp 0.5 s goes back"),
            std::string::npos);
}

// A tracker CSV's stamps never go back (rows out of order, two runs in one file), as read_tracker_csv
// has always said and the docs say: refused when read, whatever asks for the file.
TEST(TrackerFileCsv, TimeGoingBackIsRefusedWhenReadARepeatedStampIsNot) {
  const std::string e = file_error_of("t_s,x_mm,y_mm,z_mm\n1,1,2,3\n1,1,2,3\n0.5,1,2,3\n");
  EXPECT_NE(e.find("session.txt:4: column 't_s': time goes backwards (0.5 s after 1 s on line 3)"), std::string::npos)
      << e;
  EXPECT_EQ(parse_tracker_file("t_s,x_mm,y_mm,z_mm\n1,1,2,3\n1,1,2,3\n", "r.csv").points.size(), 2u);
}

// The docs say other columns are ignored: a point's name or a note in text, numbers in any unit.
TEST(TrackerFileCsv, OtherColumnsTextOrNumbersAreIgnored) {
  const TrackerFile f = parse_tracker_file(
      "point,t_s,x_mm,note,y_mm,z_mm,temperature_C\nA1,0,1500,\"seen, twice\",0,2000,21.5\nA2,0.01,1501,,1,2001,x\n",
      "run.csv");
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_DOUBLE_EQ(f.points[1].t_s, 0.01);
  EXPECT_DOUBLE_EQ(f.points[1].p_m.x(), 1.501);
  EXPECT_DOUBLE_EQ(f.points[1].p_m.z(), 2.001);
  EXPECT_EQ(f.points[1].line, 3);
  // The columns read are still checked.
  EXPECT_NE(file_error_of("note,t_s,x_mm,y_mm,z_mm\nok,0,abc,0,1\n").find("session.txt:2: column 'x_mm'"),
            std::string::npos);
  // The older reader ignores them the same way.
  EXPECT_EQ(parse_tracker_csv("name,t_s,x_mm,y_mm,z_mm\nP1,0,1,2,3\n", "old.csv").size(), 1u);
  // Positions in two units: which is it?
  EXPECT_NE(file_error_of("t_s,x_mm,y_mm,z_mm,y_m\n0,1,2,3,0.002\n").find("columns 'x_mm' and 'y_m'"),
            std::string::npos);
}

// Millimetre numbers under a "Meters" header put a 1.5 m point 1.5 km away; the documented range is
// +-100 m, named with the line and the column (the old 10 km limit let it through).
TEST(TrackerFileErrors, CoordinatesBeyondAHundredMetresNameTheirLineAndColumn) {
  const std::string e = file_error_of("// Units: Meters\n// Columns: Target X Y Z\nP1 1.5 0 0.9\nP2 1500 0 900\n");
  EXPECT_NE(e.find("session.txt:4: field 2 (x): the point lies 1500 m from the frame's origin along x, outside "
                   "-100..100 m"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("is the file in another unit than m (the header, line 1)"), std::string::npos) << e;
  const std::string z = file_error_of("// Units: Meters\nP1 1.5 0 -900\n");
  EXPECT_NE(z.find("session.txt:2: field 4 (z)"), std::string::npos) << z;
  // A spherical point 150 m out is named by its radius.
  const std::string r = file_error_of("// Units: Meters, Degrees\n// Columns: Target R Theta Phi\nP1 150 0 90\n");
  EXPECT_NE(r.find("session.txt:3: field 2 (r)"), std::string::npos) << r;
  EXPECT_NEAR(parse_tracker_file("// Units: Meters\nP1 99.5 0 -99.5\n", "s.txt").points[0].p_m.x(), 99.5, 1e-12);
}

// SA writes its header as "LABEL: VALUE": the label says what a line is, so a working frame named
// "Column C3" (not a columns line) or "Test Unit in Bay 4" (not inches) keeps its name, and what
// write_sa_export writes reads back with it.
TEST(SaExport, FrameNamesHoldingHeaderWordsReadBackAsWritten) {
  TrackerTrace t;
  for (int i = 0; i < 5; ++i) t.push_back({0.01 * i, Vector3(1.5 + 0.001 * i, 0.2, 0.9)});
  for (const char* frame : {"Column C3", "Test Unit in Bay 4", "Frame: Version 2 (Cartesian)", "Café 3°"}) {
    const auto path = std::filesystem::temp_directory_path() / "deflex_sa_frame_names.txt";
    SaExportOptions o;
    o.frame = frame;
    write_sa_export(t, path.string(), o);
    TrackerReadOptions ro;
    ro.expect_frame = frame;
    const TrackerFile f = read_tracker_file(path.string(), ro);
    std::filesystem::remove(path);
    EXPECT_EQ(f.frame, frame);
    EXPECT_EQ(f.length_unit, "mm") << frame;
    EXPECT_EQ(f.coordinates, "cartesian") << frame;
    ASSERT_EQ(f.points.size(), t.size()) << frame;
    EXPECT_NEAR(f.points[4].p_m.x(), 1.504, 1e-12) << frame;
  }
  // A note is a note: neither its words nor a colon in it make it a header line.
  const TrackerFile f = parse_tracker_file(
      "// exported for Test Unit in Bay 4, columns as usual\n// Operator note: frame check done\n"
      "// Units: Millimeters\nP1 1000 0 0\n",
      "s.txt");
  EXPECT_EQ(f.length_unit, "mm");
  EXPECT_EQ(f.frame, "");
  // Names that could not be read back are refused before anything is written.
  SaExportOptions bad;
  bad.frame = "two\nlines";
  EXPECT_THROW(write_sa_export(t, (std::filesystem::temp_directory_path() / "deflex_sa_bad.txt").string(), bad),
               InputError);
  bad = SaExportOptions{};
  bad.collection = "My Job";
  EXPECT_THROW(write_sa_export(t, (std::filesystem::temp_directory_path() / "deflex_sa_bad.txt").string(), bad),
               InputError);
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::temp_directory_path() / "deflex_sa_bad.txt"));
}

// SA on Windows exports in the ANSI code page: a frame "Caf\xE9" (0xE9 is e-acute in Windows-1252)
// and a name with 0xB0 (the degree sign) are read as UTF-8 "Café", "P°1", so the frame compares equal
// to the same name typed in UTF-8 (the frame file, --expect-frame).
TEST(SaExport, AWindows1252ExportIsReadAsUtf8) {
  const std::string text =
      "// Working Frame: Caf\xE9\n// Units: Millimeters\nP\xB0"
      "1 1000 0 0\nP\x80 1001 0 0\n";
  TrackerReadOptions o;
  o.expect_frame = "Caf\xC3\xA9";  // "Café" in UTF-8
  const TrackerFile f = parse_tracker_file(text, "s.txt", o);
  EXPECT_EQ(f.frame, "Caf\xC3\xA9");
  EXPECT_EQ(f.encoding, "windows-1252");
  EXPECT_EQ(f.points[0].name,
            "P\xC2\xB0"
            "1");
  EXPECT_EQ(f.points[1].name, "P\xE2\x82\xAC");  // 0x80: the euro sign, U+20AC
  EXPECT_EQ(parse_tracker_file("// Working Frame: Caf\xC3\xA9\n// Units: mm\nP1 1 0 0\n", "u.txt").encoding, "utf-8");
}

}  // namespace
}  // namespace deflex
