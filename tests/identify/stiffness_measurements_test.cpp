// The measurement CSV: layout, units, column order, and errors that name the file, line and column.
#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "deflex/identify/stiffness_measurements.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::string& path) {
  try {
    (void)read_stiffness_measurements(path);
  } catch (const DataError& e) {
    return e.what();
  }
  return "no error";
}

const char* const kHeader =
    "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,dx_mm,dy_mm,dz_mm\n";

TEST(StiffnessMeasurements, ReadsTheIssueLayoutInSiUnits) {
  const std::string path = write_temp("m1.csv", std::string(kHeader) +
                                                    "# a comment line\n"
                                                    "90,0,-45,0,30,180,100,-200,300,10,-20,30,0.5,-0.25,1\n");
  const auto data = read_stiffness_measurements(path);
  ASSERT_EQ(data.size(), 1u);
  const StiffnessMeasurement& m = data[0];
  ASSERT_EQ(m.q.size(), 6);
  EXPECT_DOUBLE_EQ(m.q[0], kPi / 2);
  EXPECT_DOUBLE_EQ(m.q[2], -kPi / 4);
  EXPECT_DOUBLE_EQ(m.q[5], kPi);
  EXPECT_EQ(m.wrench_base, (Wrench() << 100, -200, 300, 10, -20, 30).finished());
  EXPECT_DOUBLE_EQ(m.dp_m.x(), 0.5e-3);
  EXPECT_DOUBLE_EQ(m.dp_m.y(), -0.25e-3);
  EXPECT_DOUBLE_EQ(m.dp_m.z(), 1e-3);
  EXPECT_FALSE(m.drot_rad.has_value());
  EXPECT_EQ(m.weight, 1.0);
  EXPECT_EQ(m.line, 3);
}

TEST(StiffnessMeasurements, AnyColumnOrderOptionalOrientationAndWeightOtherUnits) {
  const std::string path = write_temp(
      "m2.csv",
      "weight,dz_m,dy_m,dx_m,drz_rad,dry_rad,drx_rad,note_x_mm,mz_Nm,my_Nm,mx_Nm,fz_N,fy_N,fx_N,q3_rad,q2_rad,q1_rad\n"
      "2.5,0.003,0.002,0.001,3e-5,2e-5,1e-5,99,6,5,4,3,2,1,0.3,0.2,0.1\n");
  const auto data = read_stiffness_measurements(path);
  ASSERT_EQ(data.size(), 1u);
  const StiffnessMeasurement& m = data[0];
  ASSERT_EQ(m.q.size(), 3);
  EXPECT_DOUBLE_EQ(m.q[2], 0.3);
  EXPECT_EQ(m.wrench_base, (Wrench() << 1, 2, 3, 4, 5, 6).finished());
  EXPECT_EQ(m.dp_m, Vector3(0.001, 0.002, 0.003));
  ASSERT_TRUE(m.drot_rad.has_value());
  EXPECT_EQ(*m.drot_rad, Vector3(1e-5, 2e-5, 3e-5));
  EXPECT_EQ(m.weight, 2.5);
}

TEST(StiffnessMeasurements, WriteThenReadGivesTheSameMeasurements) {
  StiffnessMeasurement m;
  m.q = JointVector::LinSpaced(6, -1.0, 1.0);
  m.wrench_base << 123.5, -50, 900, 1.5, -2.5, 3.5;
  m.dp_m = Vector3(1.234e-4, -5.6e-4, 7.89e-4);
  m.drot_rad = Vector3(1e-5, -2e-5, 3e-5);
  m.weight = 0.5;
  const std::string path = ::testing::TempDir() + "m3.csv";
  write_stiffness_measurements(path, {m, m}, {"made by a test"});
  const auto back = read_stiffness_measurements(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_LT((back[1].q - m.q).norm(), 1e-9);
  EXPECT_LT((back[1].wrench_base - m.wrench_base).norm(), 1e-9);
  EXPECT_LT((back[1].dp_m - m.dp_m).norm(), 1e-12);
  EXPECT_LT((*back[1].drot_rad - *m.drot_rad).norm(), 1e-12);
  EXPECT_EQ(back[1].weight, 0.5);
}

TEST(StiffnessMeasurements, BadFilesNameTheFileLineAndColumn) {
  const std::string h = kHeader;
  std::string e = error_of(write_temp("b1.csv", h + "0,0,0,0,0,0,1,2,3,4,5,6,0.1,0.2,nan\n"));
  EXPECT_NE(e.find("b1.csv:2"), std::string::npos) << e;
  EXPECT_NE(e.find("dz_mm"), std::string::npos) << e;

  e = error_of(write_temp("b2.csv", h + "0,0,0,0,0,0,1,2,3,4,5,6,0.1,0.2,0.3\n0,0,0,0,0,0,1,2,3,4,5,,0.1,0.2,0.3\n"));
  EXPECT_NE(e.find("b2.csv:3"), std::string::npos) << e;
  EXPECT_NE(e.find("mz_Nm"), std::string::npos) << e;

  e = error_of(
      write_temp("b3.csv", "q1_deg,q2_deg,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,dx_mm,dy_mm\n0,0,1,2,3,4,5,6,0.1,0.2\n"));
  EXPECT_NE(e.find("dz_mm"), std::string::npos) << e;

  e = error_of(write_temp("b4.csv", "fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,dx_mm,dy_mm,dz_mm\n1,2,3,4,5,6,0.1,0.2,0.3\n"));
  EXPECT_NE(e.find("q1_deg"), std::string::npos) << e;

  // A displacement in metres typed into a mm column would be 1000 times too small; one in um
  // typed into mm 1000 times too large: the latter is caught.
  e = error_of(write_temp("b5.csv", h + "0,0,0,0,0,0,1,2,3,4,5,6,150,0.2,0.3\n"));
  EXPECT_NE(e.find("b5.csv:2"), std::string::npos) << e;
  EXPECT_NE(e.find("dx_mm"), std::string::npos) << e;

  e = error_of(
      write_temp("b6.csv", std::string("weight,") + h.substr(0, h.size() - 1) + "\n0,0,0,0,0,0,0,1,2,3,4,5,6,1,2,3\n"));
  EXPECT_NE(e.find("weight"), std::string::npos) << e;
  EXPECT_NE(e.find(":2"), std::string::npos) << e;

  e = error_of(write_temp("b7.csv", h));
  EXPECT_NE(e.find("no measurement rows"), std::string::npos) << e;

  e = error_of(write_temp("b8.csv", h.substr(0, h.size() - 1) + ",drx_rad\n0,0,0,0,0,0,1,2,3,4,5,6,0.1,0.2,0.3,0\n"));
  EXPECT_NE(e.find("drx_rad, dry_rad, drz_rad"), std::string::npos) << e;

  e = error_of(write_temp("b9.csv", h + "0,0,0,0,0,0,1,2,3,4,5,abc,0.1,0.2,0.3\n"));
  EXPECT_NE(e.find("b9.csv:2"), std::string::npos) << e;

  EXPECT_NE(error_of(::testing::TempDir() + "does_not_exist.csv").find("does_not_exist.csv"), std::string::npos);
}

}  // namespace
}  // namespace deflex
