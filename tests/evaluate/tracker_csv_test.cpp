// Tracker CSV files: columns in any order, units, and errors that name the file, line and column.
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_tracker_csv(text, "run.csv");
  } catch (const DataError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TrackerCsv, ColumnsInAnyOrderInMillimetres) {
  const TrackerTrace t = parse_tracker_csv(
      "# tracker export\nz_mm,quality,t_s,x_mm,y_mm\n3,1,0.000,1000,2\n\n4.5,1,0.001,1000.25,-2\n", "run.csv");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[0].t_s, 0.0);
  EXPECT_DOUBLE_EQ(t[0].p_m.x(), 1.0);
  EXPECT_DOUBLE_EQ(t[0].p_m.y(), 0.002);
  EXPECT_DOUBLE_EQ(t[0].p_m.z(), 0.003);
  EXPECT_DOUBLE_EQ(t[1].t_s, 0.001);
  EXPECT_DOUBLE_EQ(t[1].p_m.x(), 1.00025);
  EXPECT_DOUBLE_EQ(t[1].p_m.z(), 0.0045);
}

TEST(TrackerCsv, ErrorsNameFileLineAndColumn) {
  const std::string missing = error_of("t_s,x_mm,y_mm\n0,1,2\n");
  EXPECT_NE(missing.find("run.csv"), std::string::npos) << missing;
  EXPECT_NE(missing.find("z_mm"), std::string::npos) << missing;

  const std::string nan = error_of("t_s,x_mm,y_mm,z_mm\n0,1,2,3\n0.001,1,nan,3\n");
  EXPECT_NE(nan.find("run.csv:3"), std::string::npos) << nan;
  EXPECT_NE(nan.find("y_mm"), std::string::npos) << nan;

  const std::string garbage = error_of("t_s,x_mm,y_mm,z_mm\n0,1,2,3\n0.001,1,2,3.1.2\n");
  EXPECT_NE(garbage.find("run.csv:3"), std::string::npos) << garbage;
  EXPECT_NE(garbage.find("z_mm"), std::string::npos) << garbage;

  const std::string back = error_of("t_s,x_mm,y_mm,z_mm\n0.5,1,2,3\n0.4,1,2,3\n");
  EXPECT_NE(back.find("run.csv:3"), std::string::npos) << back;
  EXPECT_NE(back.find("t_s"), std::string::npos) << back;
  EXPECT_NE(back.find("backwards"), std::string::npos) << back;

  const std::string empty = error_of("t_s,x_mm,y_mm,z_mm\n");
  EXPECT_NE(empty.find("no samples"), std::string::npos) << empty;

  const std::string cells = error_of("t_s,x_mm,y_mm,z_mm\n0,1,2\n");
  EXPECT_NE(cells.find("run.csv:2"), std::string::npos) << cells;
}

TEST(TrackerCsv, WriteThenReadRoundTrip) {
  const auto path = (std::filesystem::temp_directory_path() / "deflex_tracker_roundtrip.csv").string();
  const TrackerTrace t{{0.0, Vector3(1.234567891, -0.5, 0.75)}, {0.001, Vector3(1.2345679, -0.5000001, 0.7500002)}};
  write_tracker_csv(t, path);
  const TrackerTrace back = read_tracker_csv(path);
  ASSERT_EQ(back.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_DOUBLE_EQ(back[i].t_s, t[i].t_s);
    EXPECT_NEAR((back[i].p_m - t[i].p_m).norm(), 0.0, 1e-9);  // 10 significant digits of mm
  }
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "t_s,x_mm,y_mm,z_mm");
  std::remove(path.c_str());
  EXPECT_THROW(read_tracker_csv(path), DataError);  // the file is gone: a clear error, not a crash
}

TEST(TrackerCsv, LengthOfAPolyline) {
  const TrackerTrace t{{0.0, Vector3(0, 0, 0)}, {1.0, Vector3(3e-3, 4e-3, 0)}, {2.0, Vector3(3e-3, 4e-3, 1e-3)}};
  EXPECT_NEAR(trace_length_m(t), 6e-3, 1e-15);
}

}  // namespace
}  // namespace deflex
