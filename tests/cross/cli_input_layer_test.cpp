// What the input layer must accept and write back (the bad inputs are in tests/sweep): a wrench
// table with a byte order mark or CR-only line endings means the same as a plain one, names and
// notes with quotes and backslashes survive a robot file round trip, and the messages that tell a
// user what to change.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cross/cli_runner.hpp"

namespace deflex::test {
namespace {

namespace fs = std::filesystem;
const std::string kSourceDir = DEFLEX_SOURCE_DIR;

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("deflex_input_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) {
    s.replace(p, from.size(), to);
  }
  return s;
}

TEST(CliInput, WrenchTableWithByteOrderMarkOrCrLinesMeansTheSame) {
  const fs::path d = scratch("bom");
  const std::string table = slurp(kSourceDir + "/examples/offline/square_wrench.csv");
  std::ofstream(d / "bom.csv", std::ios::binary) << "\xEF\xBB\xBF" << table;
  std::ofstream(d / "cr.csv", std::ios::binary) << replace_all(table, "\n", "\r");
  std::ofstream(d / "crlf.csv", std::ios::binary) << replace_all(table, "\n", "\r\n");
  const std::string path = " --path " + kSourceDir + "/examples/offline/square_path.csv --force table:";
  const auto plain =
      run_cli("offline" + path + kSourceDir + "/examples/offline/square_wrench.csv -o " + (d / "plain.out").string());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  for (const char* name : {"bom", "cr", "crlf"}) {
    const auto r = run_cli("offline" + path + (d / (std::string(name) + ".csv")).string() + " -o " +
                           (d / (std::string(name) + ".out")).string());
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    // Same compensated path, point for point (the files differ only in the comment naming the table).
    const auto strip = [](std::string s) {
      std::string out;
      std::istringstream in(s);
      for (std::string l; std::getline(in, l);) {
        if (l.rfind("#", 0) != 0) out += l + "\n";
      }
      return out;
    };
    EXPECT_EQ(strip(slurp(d / (std::string(name) + ".out"))), strip(slurp(d / "plain.out"))) << name;
  }
  fs::remove_all(d);
}

TEST(CliInput, RobotFileWithQuotesAndBackslashesReadsBack) {
  const fs::path d = scratch("quotes");
  std::string robot = slurp(kSourceDir + "/examples/robots/kuka_kr210_r2700.yaml");
  robot = replace_all(robot, "name: \"KUKA KR 210 R2700-class (approximate)\"", "name: 'KR 210 \"test\" C:\\cell\\1'");
  std::ofstream(d / "in.yaml") << robot;
  const auto printed = run_cli("robot --robot " + (d / "in.yaml").string());
  ASSERT_EQ(printed.exit_code, 0) << printed.err;
  std::ofstream(d / "out.yaml") << printed.out;
  const auto fk = run_cli("fk --robot " + (d / "out.yaml").string() + " --joints-deg 0,30,10,0,50,0");
  ASSERT_EQ(fk.exit_code, 0) << fk.err << "\n" << printed.out;
  EXPECT_NE(fk.out.find("robot: KR 210 \"test\" C:\\cell\\1"), std::string::npos) << fk.out;
  fs::remove_all(d);
}

TEST(CliInput, RobotJsonCarriesTheDescription) {
  const auto r = run_cli("robot --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["dof"], 6);
  EXPECT_EQ(doc["stiffness_Nm_per_rad"].size(), 6U);
  EXPECT_NE(doc["yaml"].get<std::string>().find("deflex_robot: 1"), std::string::npos);
}

TEST(CliInput, PlanCalibrationSaysWhatToChangeWhenTheTcpIsOnTheLastAxis) {
  const fs::path d = scratch("plan");
  const auto r = run_cli("plan-calibration --robot builtin --region-mm 1300,1900,-400,400,500,1100 --load-N 800 -o " +
                         (d / "plan.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("lies on axis 6"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--fix-stiffness-Nm-per-rad 6="), std::string::npos) << r.err;
  fs::remove_all(d);
}

TEST(CliInput, IdentifyFromOneRowIdentifiesNothing) {
  const fs::path d = scratch("one_row");
  std::ifstream in(kSourceDir + "/examples/identify/kr210_synthetic_measurements.csv");
  std::string text, line;
  int data_rows = 0;
  while (std::getline(in, line) && data_rows < 1) {
    text += line + "\n";
    data_rows += (line.empty() || line[0] == '#' || line.rfind("q1_deg", 0) == 0) ? 0 : 1;
  }
  std::ofstream(d / "one.csv") << text;
  const auto r = run_cli("identify --robot " + kSourceDir + "/examples/robots/kuka_kr210_r2700.yaml --data " +
                         (d / "one.csv").string() + " --write-robot " + (d / "out.yaml").string());
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("no joint can be identified"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "out.yaml"));
  fs::remove_all(d);
}

TEST(CliInput, HelpAndVersionStillExitZero) {
  EXPECT_EQ(run_cli("--help").exit_code, 0);
  EXPECT_EQ(run_cli("fk --help").exit_code, 0);
  EXPECT_EQ(run_cli("--version").exit_code, 0);
}

}  // namespace
}  // namespace deflex::test
