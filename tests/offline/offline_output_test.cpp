// Offline outputs: the CSV read back through the project's reader, and the RAPID module through an
// independent well-formedness checker (which is itself shown to catch broken modules).
#include <cstdio>
#include <fstream>
#include <regex>

#include <gtest/gtest.h>

#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/offline/offline_summary.hpp"
#include "deflex/offline/rapid_module.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "rapid_checker.hpp"

namespace deflex {
namespace {

struct Compensated {
  RobotModel model = builtin_irb6700();
  std::vector<Pose> poses = sample_circle(default_circle(), Eigen::Quaterniond(0, 0, 1, 0));
  OfflineResult result = compensate_path(model, solve_path_ik(model, poses, IkRequest{}), poses,
                                         LdbbForceModel(Vector3(1.5, 0.0, 0.9), 625.0, true));
};

std::string replace_first(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  return at == std::string::npos ? s : s.replace(at, from.size(), to);
}

TEST(OfflineCsv, RowsReadBackInMillimetresAndDegrees) {
  const Compensated c;
  const std::string path = ::testing::TempDir() + "offline_test.csv";
  write_offline_csv(c.result, path);
  const CsvTable t = CsvTable::read_file(path);
  ASSERT_EQ(t.rows(), 81u);
  t.require({"index", "q1_des_deg", "q6_cmd_deg", "x_cmd_mm", "qw_des", "cfx_cmd", "fx_N", "mz_Nm", "deflection_mm",
             "residual_mm"});
  for (std::size_t i = 0; i < t.rows(); i += 8) {
    const OfflinePoint& p = c.result.points[i];
    EXPECT_EQ(t.at(i, "index"), static_cast<double>(i));
    EXPECT_NEAR(t.at(i, "q2_cmd_deg"), p.q_command[1] * 180.0 / kPi, 1e-8);
    EXPECT_NEAR(t.at(i, "x_des_mm"), p.tcp_desired.translation().x() * 1000.0, 1e-6);
    EXPECT_NEAR(t.at(i, "z_cmd_mm"), p.tcp_command.translation().z() * 1000.0, 1e-6);
    EXPECT_NEAR(t.at(i, "fz_N"), p.wrench_base[2], 1e-7);
    EXPECT_NEAR(t.at(i, "deflection_mm"), p.predicted_deflection.head<3>().norm() * 1000.0, 1e-9);
    EXPECT_NEAR(t.at(i, "deflection_rx_mrad"), p.predicted_deflection[3] * 1000.0, 1e-9);
    EXPECT_LT(t.at(i, "residual_mm"), 1e-6);
  }
  // Quaternion signs: the tool points down (0, 0, 1, 0) and the command tilts it by under 1 mrad, so
  // desired and commanded quaternions must both stay near +(0, 0, 1, 0), never flip to the
  // equivalent negative (a reader would see a 360 deg jump).
  for (std::size_t i = 0; i < t.rows(); ++i) {
    EXPECT_NEAR(t.at(i, "qy_des"), 1.0, 1e-12) << i;
    EXPECT_GT(t.at(i, "qy_cmd"), 0.999) << i;
  }
  std::remove(path.c_str());
  EXPECT_THROW(write_offline_csv(c.result, "/dev/null/dir/out.csv"), Error);
}

TEST(RapidModule, MoveAbsJModuleIsWellFormedAndHoldsTheCompensatedJoints) {
  const Compensated c;
  RapidOptions o;
  o.speed_mm_s = 30.0;
  o.note = "line one\nline two";
  const std::string text = rapid_module(c.result, o);
  const test::RapidCheck check = test::check_rapid_module(text, c.model);
  EXPECT_TRUE(check.problems.empty()) << ::testing::PrintToString(check.problems) << "\n" << text;
  EXPECT_EQ(check.module_name, "DeflexOffline");
  ASSERT_EQ(check.moved_to.size(), 81u);
  EXPECT_EQ(check.declarations.at("vDeflex").value, "[30,500,5000,1000]");
  for (std::size_t i = 0; i < 81; ++i) {
    const test::RapidDeclaration& d = check.declarations.at(check.moved_to[i]);
    ASSERT_EQ(d.type, "jointtarget");
    const auto v = test::rapid_numbers(d.value);
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(v[static_cast<std::size_t>(j)], c.result.points[i].q_command[j] * 180.0 / kPi, 0.51e-4);
    }
  }
  EXPECT_NE(text.find("! Force model: LDBB push 625 N"), std::string::npos);
  EXPECT_NE(text.find("zone fine"), std::string::npos);
  EXPECT_NE(text.find("! line two"), std::string::npos);
}

TEST(RapidModule, MoveLModuleCarriesPosesAndConfdata) {
  const Compensated c;
  RapidOptions o;
  o.motion = RapidMotion::kMoveL;
  o.zone = "z1";
  o.module_name = "Circle625";
  const std::string text = rapid_module(c.result, o);
  const test::RapidCheck check = test::check_rapid_module(text, c.model);
  EXPECT_TRUE(check.problems.empty()) << ::testing::PrintToString(check.problems) << "\n" << text;
  ASSERT_EQ(check.moved_to.size(), 81u);
  for (std::size_t i = 0; i < 81; i += 5) {
    const auto v = test::rapid_numbers(check.declarations.at(check.moved_to[i]).value);
    const OfflinePoint& p = c.result.points[i];
    EXPECT_NEAR(v[0], p.tcp_command.translation().x() * 1000.0, 0.51e-4);
    EXPECT_NEAR(v[2], p.tcp_command.translation().z() * 1000.0, 0.51e-4);
    Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
    EXPECT_LT(q.angularDistance(Eigen::Quaterniond(p.tcp_command.linear())), 1e-7);
    EXPECT_EQ(static_cast<int>(v[10]), p.configuration_command.cfx);
    EXPECT_GT(v[5], 0.999);  // sign continuous along the path, near +(0, 0, 1, 0)
  }
  EXPECT_NE(text.find("ConfL\\On;"), std::string::npos);
}

TEST(RapidModule, CheckerCatchesBrokenModules) {
  const Compensated c;
  const std::string good = rapid_module(c.result, RapidOptions{});
  ASSERT_TRUE(test::check_rapid_module(good, c.model).problems.empty());
  const auto problems = [&](const std::string& text) {
    return ::testing::PrintToString(test::check_rapid_module(text, c.model).problems);
  };
  // A target never moved to; a move to an undeclared target; a missing ENDPROC; a joint out of range.
  EXPECT_NE(problems(std::regex_replace(good, std::regex(R"(    MoveAbsJ jt040\\NoEOffs[^\n]*\n)"), ""))
                .find("'jt040' declared but never used"),
            std::string::npos);
  EXPECT_NE(problems(replace_first(good, "MoveAbsJ jt040", "MoveAbsJ jt999")).find("'jt999' used but not declared"),
            std::string::npos);
  EXPECT_NE(problems(replace_first(good, "  ENDPROC\n", "")).find("PROC without ENDPROC"), std::string::npos);
  EXPECT_NE(problems(std::regex_replace(good, std::regex(R"(jt005:=\[\[[-0-9.]+)"), "jt005:=[[250.0")).find("joint 1"),
            std::string::npos);
  EXPECT_NE(problems(replace_first(good, "ENDMODULE", "")).find("ENDMODULE"), std::string::npos);
}

TEST(RapidModule, RejectsBadOptions) {
  const Compensated c;
  RapidOptions o;
  o.module_name = "1bad";
  EXPECT_THROW((void)rapid_module(c.result, o), InputError);
  o = RapidOptions{};
  o.zone = "z7";
  EXPECT_THROW((void)rapid_module(c.result, o), InputError);
  o = RapidOptions{};
  o.speed_mm_s = 0.0;
  EXPECT_THROW((void)rapid_module(c.result, o), InputError);
  o = RapidOptions{};
  o.tool = "my tool";
  EXPECT_THROW((void)rapid_module(c.result, o), InputError);
  EXPECT_THROW((void)rapid_module(OfflineResult{}, RapidOptions{}), InputError);
}

TEST(OfflineSummary, StatesTheFiguresInMillimetres) {
  const Compensated c;
  const std::string s = offline_summary(c.result);
  char expected[64];
  std::snprintf(expected, sizeof expected, "max %.4f mm, mean %.4f mm", c.result.max_deflection_m * 1000.0,
                c.result.mean_deflection_m * 1000.0);
  EXPECT_NE(s.find(expected), std::string::npos) << s;
  EXPECT_NE(s.find("points: 81"), std::string::npos);
}

}  // namespace
}  // namespace deflex
