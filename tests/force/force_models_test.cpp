// Force models: the LDBB bar force against a direction worked out here from the rig's geometry,
// the spec syntax, the constant wrench and the wrench table with its file/line/column errors.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/force/tool_wrench_model.hpp"
#include "deflex/force/wrench_table_model.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

Pose at(const Vector3& p) {
  Pose pose = Pose::Identity();
  pose.translation() = p;
  return pose;
}

using test::error_of;

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

// The rig of the paper's Figure 4: pivot on the table below the circle centre by h, TCP ball on a
// circle of radius r. At angle a the bar runs from the pivot to (r cos a, r sin a, h) relative to
// it, so a push of F is F (r cos a, r sin a, h) / sqrt(r^2 + h^2) and the bar's inclination to the
// XY plane is atan(h / r) whatever a is.
TEST(LdbbForceModel, PushAlongTheBarAgainstTheRigGeometry) {
  const double r = 0.1, h = 0.0839, F = 625.0;  // h = r tan(40 deg)
  const Vector3 centre(1.5, 0.0, 1.0);
  const Vector3 pivot = centre - Vector3(0, 0, h);
  const LdbbForceModel push(pivot, F, true);
  const LdbbForceModel pull(pivot, F, false);
  for (int k = 0; k < 16; ++k) {
    const double a = 2 * kPi * k / 16.0;
    const Pose tcp = at(centre + Vector3(r * std::cos(a), r * std::sin(a), 0.0));
    const Vector3 expected = F * Vector3(r * std::cos(a), r * std::sin(a), h) / std::sqrt(r * r + h * h);
    const Wrench w = push.wrench_at(static_cast<std::size_t>(k), tcp);
    EXPECT_NEAR((w.head<3>() - expected).norm(), 0.0, 1e-9) << k;
    EXPECT_EQ(w.tail<3>(), Vector3::Zero());
    EXPECT_NEAR((pull.wrench_at(0, tcp).head<3>() + expected).norm(), 0.0, 1e-9);
    EXPECT_NEAR(push.inclination_rad(tcp), std::atan2(h, r), 1e-12);
    EXPECT_NEAR(push.bar_length_m(tcp), std::hypot(r, h), 1e-12);
  }
  EXPECT_THROW((void)push.wrench_at(3, at(pivot)), InputError);
  EXPECT_THROW(LdbbForceModel(pivot, -1.0, true), InputError);
  EXPECT_THROW(LdbbForceModel(pivot, std::nan(""), true), InputError);
}

TEST(ForceSpec, LdbbWithPivotAndSeveralLoads) {
  const auto models = parse_force_specs("ldbb:pivot_mm=1500;0;900,force_N=125;375;625,mode=pull");
  ASSERT_EQ(models.size(), 3u);
  const double loads[3] = {125.0, 375.0, 625.0};
  for (int k = 0; k < 3; ++k) {
    const auto* m = dynamic_cast<const LdbbForceModel*>(models[static_cast<std::size_t>(k)].get());
    ASSERT_NE(m, nullptr);
    EXPECT_DOUBLE_EQ(m->force_N(), loads[k]);
    EXPECT_FALSE(m->push());
    EXPECT_NEAR((m->pivot_base_m() - Vector3(1.5, 0, 0.9)).norm(), 0.0, 1e-15);
  }
  EXPECT_EQ(models[2]->label(), "ldbb_625N_pull");
  EXPECT_THROW((void)parse_force_spec("ldbb:pivot_mm=1500;0;900,force_N=125;375"), InputError);
}

TEST(ForceSpec, LdbbPhiPlacesThePivotOnTheCircleAxis) {
  const CirclePath circle = default_circle();  // centre (1.5, 0, 1.0) m, r = 0.1 m, normal +z
  ForceSpecContext ctx;
  ctx.circle = circle;
  const auto model = parse_force_spec("ldbb:phi_deg=45,force_N=625", ctx);
  const auto* ldbb = dynamic_cast<const LdbbForceModel*>(model.get());
  ASSERT_NE(ldbb, nullptr);
  EXPECT_TRUE(ldbb->push());
  // tan 45 = 1: the pivot is one radius below the centre, the bar sqrt(2) * 100 mm long.
  EXPECT_NEAR((ldbb->pivot_base_m() - Vector3(1.5, 0.0, 0.9)).norm(), 0.0, 1e-15);
  for (const Pose& p : sample_circle(circle, Eigen::Quaterniond(0, 0, 1, 0))) {
    EXPECT_NEAR(ldbb->inclination_rad(p), deg_to_rad(45.0), 1e-12);
    EXPECT_NEAR(ldbb->bar_length_m(p), 0.1 * std::sqrt(2.0), 1e-12);
  }
}

TEST(ForceSpec, ErrorsQuoteTheSpecAndKey) {
  ForceSpecContext ctx;
  ctx.circle = default_circle();
  EXPECT_NE(error_of([] { (void)parse_force_specs("ldbb:pivot_mm=1;2;3"); }).find("'force_N'"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("ldbb:phi_deg=30,force_N=100"); }).find("needs a circle"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              (void)parse_force_specs("ldbb:phi_deg=30,pivot_mm=1;2;3,force_N=100", ctx);
            }).find("exactly one of"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("ldbb:pivot_mm=1;2;3,force_N=100,mode=shove"); }).find("'mode'"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("ldbb:pivot_mm=1;2;3,force_N=-100"); }).find("not a positive"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("ldbb:pivot_mm=1;2;3,force=100"); }).find("unknown key 'force'"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("ldbb:pivot_mm=1;2;nan,force_N=100"); }).find("'nan'"),
            std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("spring:k=3"); }).find("unknown kind 'spring'"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("constant:"); }).find("at least one"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_specs("table:"); }).find("CSV file"), std::string::npos);
  EXPECT_THROW((void)parse_force_specs("table:/nonexistent/wrench.csv"), Error);
  EXPECT_THROW((void)ldbb_pivot_for_circle(default_circle(), deg_to_rad(90.0)), InputError);
}

TEST(ConstantWrench, SameWrenchEverywhere) {
  const auto model = parse_force_spec("constant:fz_N=-200,mx_Nm=3.5");
  Wrench expected;
  expected << 0, 0, -200, 3.5, 0, 0;
  EXPECT_EQ(model->wrench_at(0, at(Vector3(1, 2, 3))), expected);
  EXPECT_EQ(model->wrench_at(99, at(Vector3(-1, 0, 0))), expected);
  EXPECT_FALSE(model->points().has_value());
  Wrench bad = expected;
  bad[1] = std::nan("");
  EXPECT_THROW(ConstantWrenchModel{bad}, InputError);
}

TEST(ToolWrench, TurnsWithTheTool) {
  // A drill pushed along its own axis feels the thrust back along -z of the tool. Tool pointing
  // down (rotated by pi about base y): the workpiece pushes the robot up, +z in the base frame.
  const auto m = parse_force_spec("tool:fz_N=-200,mz_Nm=3");
  EXPECT_EQ(m->label(), "tool");
  Pose down = at(Vector3(1.5, 0.2, 0.8));
  down.linear() = Eigen::AngleAxisd(kPi, Vector3::UnitY()).toRotationMatrix();
  const Wrench w = m->wrench_at(0, down);
  EXPECT_NEAR(w[2], 200.0, 1e-12);
  EXPECT_NEAR(w[5], -3.0, 1e-12);  // the drilling torque about the tool axis, seen from the base
  EXPECT_NEAR(w.head<2>().norm() + w.segment<2>(3).norm(), 0.0, 1e-12);
  // Tool along base +x (rotated by +pi/2 about y): the thrust points along -x.
  Pose forward = at(Vector3(1.5, 0.0, 1.0));
  forward.linear() = Eigen::AngleAxisd(kPi / 2, Vector3::UnitY()).toRotationMatrix();
  EXPECT_NEAR(m->wrench_at(7, forward)[0], -200.0, 1e-12);
  EXPECT_NE(m->describe().find("tool frame"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_spec("tool:"); }).find("at least one"), std::string::npos);
  EXPECT_NE(error_of([] { (void)parse_force_spec("tool:fq_N=3"); }).find("fq_N"), std::string::npos);
}

TEST(WrenchTable, RowsByOrderOrByIndex) {
  const WrenchTableModel plain(CsvTable::parse("fx_N,fy_N,fz_N\n1,2,3\n4,5,6\n", "w.csv"));
  ASSERT_EQ(plain.points(), 2u);
  EXPECT_EQ(plain.wrench_at(1, Pose::Identity()), (Wrench() << 4, 5, 6, 0, 0, 0).finished());
  const WrenchTableModel indexed(
      CsvTable::parse("index,mz_Nm,fx_N,fy_N,fz_N\n2,0.5,30,0,0\n0,0,10,0,0\n1,0,20,0,0\n", "w.csv"));
  EXPECT_DOUBLE_EQ(indexed.wrench_at(0, Pose::Identity())[0], 10.0);
  EXPECT_DOUBLE_EQ(indexed.wrench_at(2, Pose::Identity())[0], 30.0);
  EXPECT_DOUBLE_EQ(indexed.wrench_at(2, Pose::Identity())[5], 0.5);
  EXPECT_NE(error_of([&] { (void)indexed.wrench_at(3, Pose::Identity()); }).find("no wrench for path point 3"),
            std::string::npos);
}

TEST(WrenchTable, MalformedFilesNameLineAndColumn) {
  const std::string garbage = write_temp("wrench_garbage.csv", "fx_N,fy_N,fz_N\n1,2,3\n4,five,6\n");
  const std::string m = error_of([&] { (void)parse_force_spec("table:" + garbage); });
  EXPECT_NE(m.find(garbage + ":3"), std::string::npos) << m;
  EXPECT_NE(m.find("fy_N"), std::string::npos) << m;
  const auto parse_error = [](const std::string& text) {
    return error_of([&] { (void)WrenchTableModel(CsvTable::parse(text, "w.csv")); });
  };
  EXPECT_NE(parse_error("fx_N,fy_N\n1,2\n").find("fz_N"), std::string::npos);
  EXPECT_NE(parse_error("index,fx_N,fy_N,fz_N\n0,1,2,3\n0,1,2,3\n")
                .find("w.csv:3: column 'index': index 0 already "
                      "given on line 2"),
            std::string::npos);
  EXPECT_NE(parse_error("index,fx_N,fy_N,fz_N\n0.5,1,2,3\n").find("w.csv:2: column 'index'"), std::string::npos);
  EXPECT_NE(parse_error("index,fx_N,fy_N,fz_N\n0,1,2,3\n5,1,2,3\n").find("w.csv:3: column 'index'"), std::string::npos);
  EXPECT_NE(parse_error("fx_N,fy_N,fz_N\n1,2\n").find("w.csv:2"), std::string::npos);
  EXPECT_EQ(parse_error("fx_N,fy_N,fz_N\n"), "w.csv: no wrench rows");
}

}  // namespace
}  // namespace deflex
