// `deflex case-study` end to end through the real binary (DEFLEX_CLI) on a short case: the JSON
// layout of issue 7, the files of the report, the paper's figures beside ours, and a clear error
// for a bad case file.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Result run(const std::string& args, const fs::path& dir) {
  const fs::path err = dir / "stderr.txt";
  const std::string cmd = std::string(DEFLEX_CLI) + " " + args + " 2>" + err.string();
  Result r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err);
  return r;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

class CaseStudyCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("deflex_case_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    std::string text = slurp(fs::path(DEFLEX_SOURCE_DIR) / "data/cases/paper.yaml");
    text = replaced(text, "speeds_mm_s: [10, 30, 50]", "speeds_mm_s: [40, 50]");
    text = replaced(text, "laps_ccw: 3", "laps_ccw: 0");
    text = replaced(text, "settle_s: 2.0", "settle_s: 0.5");
    text = replaced(text, "seeds: 4", "seeds: 1");
    short_case_ = text;
    std::ofstream(dir_ / "short.yaml") << text;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  std::string short_case_;
};

TEST_F(CaseStudyCli, JsonHasTheIssueLayoutAndTheReportIsWritten) {
  const fs::path out = dir_ / "out" / "nested";  // made as every output's folder is
  const Result r = run("case-study --case " + (dir_ / "short.yaml").string() +
                           " --quick --no-sweep --no-budget --json --out " + out.string(),
                       dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);  // stdout is only the document
  ASSERT_TRUE(doc.contains("setups"));
  ASSERT_GE(doc["setups"].size(), 2u);
  EXPECT_EQ(doc["setups"][0]["setup"], "offline");
  EXPECT_EQ(doc["setups"][1]["setup"], "online");
  for (const auto& setup : doc["setups"]) {
    double previous_uc = 0.0;
    for (const auto& load : setup["loads"]) {
      ASSERT_TRUE(load.contains("load_N"));
      for (const char* speed : {"40", "50"}) {
        const double uc = load["uc_mm"][speed];
        const double c = load["c_mm"][speed];
        EXPECT_GT(uc, 0.0);
        EXPECT_LT(c, uc);
        EXPECT_NEAR(load["compensation"][speed].get<double>(), 1.0 - c / uc, 1e-9);
      }
      const double uc50 = load["uc_mm"]["50"];
      EXPECT_GT(uc50, previous_uc);  // loads are listed in increasing order
      previous_uc = uc50;
    }
  }
  EXPECT_EQ(doc["setups"][0]["loads"][0]["load_N"], 125);
  for (const char* f : {"report.html", "figure5.svg", "tables.csv", "tables.md"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  const std::string html = slurp(out / "report.html");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  // Self-contained: no scripts, nothing fetched from the network.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("href=\"http"), std::string::npos);
  EXPECT_NE(r.err.find("deflex case-study"), std::string::npos);  // messages go to stderr
  // stderr is a file here, not a terminal: progress as plain lines, a tenth of the way each, and no
  // carriage return (a redrawn bar left one line of some 50 kB in a log).
  EXPECT_EQ(r.err.find('\r'), std::string::npos);
  EXPECT_NE(r.err.find("deflex case-study: 100 %"), std::string::npos) << r.err;
  std::size_t progress_lines = 0;
  for (std::size_t at = r.err.find(" %"); at != std::string::npos; at = r.err.find(" %", at + 1)) ++progress_lines;
  EXPECT_LE(progress_lines, 11u) << r.err;
  EXPECT_LT(r.err.size(), 4000u) << r.err;
}

TEST_F(CaseStudyCli, TextPrintsThePapersFiguresBesideOurs) {
  const Result r = run("case-study --case " + (dir_ / "short.yaml").string() +
                           " --quick --no-sweep --no-budget --no-progress --out " + (dir_ / "out2").string(),
                       dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Table 1"), std::string::npos);
  EXPECT_NE(r.out.find("Table 2"), std::string::npos);
  EXPECT_NE(r.out.find("(0.12)"), std::string::npos);  // Table 1, 125 N, UC of the paper
  EXPECT_NE(r.out.find("(1.10)"), std::string::npos);  // Table 2, 650 N
}

TEST_F(CaseStudyCli, SeedsSpreadAndTracesThatDeflexEvaluateReads) {
  const fs::path out = dir_ / "out3";
  const fs::path traces = dir_ / "traces";
  const Result r = run("case-study --case " + (dir_ / "short.yaml").string() + " --quick --no-sweep --no-budget " +
                           "--no-progress --seeds 2 --write-traces " + traces.string() + " --out " + out.string(),
                       dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("2 seeds"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find(" ±"), std::string::npos) << r.out;  // the spread beside each mean
  const nlohmann::json doc = nlohmann::json::parse(slurp(out / "results.json"));
  EXPECT_EQ(doc["seeds"].size(), 2u);
  EXPECT_EQ(doc["setups"][1]["loads"][2]["c_mm_by_seed"]["50"].size(), 2u);
  // The traces: deflex evaluate, on the unloaded and uncompensated runs of the online setup at
  // 650 N and 50 mm/s, gives the table's first-seed UC (the same nearest-point metric, to the
  // mean of the unloaded laps).
  const fs::path unloaded = traces / "sensor-egm-joint_unloaded_50mm_s.csv";
  const fs::path uc = traces / "sensor-egm-joint_uc_650N_50mm_s.csv";
  ASSERT_TRUE(fs::exists(unloaded)) << r.out;
  ASSERT_TRUE(fs::exists(uc)) << r.out;
  EXPECT_TRUE(fs::exists(traces / "sensor-egm-joint_online_650N_50mm_s.csv"));
  EXPECT_TRUE(fs::exists(traces / "offline-program_offline_625N_50mm_s.csv"));
  const Result e =
      run("evaluate --split-laps --mean-reference --json --unloaded " + unloaded.string() + " --loaded " + uc.string(),
          dir_);
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const nlohmann::json ev = nlohmann::json::parse(e.out);
  const double table_uc = doc["setups"][1]["loads"][2]["uc_mm_by_seed"]["50"][0];
  ASSERT_TRUE(ev.contains("mean_deformation_mm")) << ev.dump(2);
  EXPECT_NEAR(ev["mean_deformation_mm"].get<double>(), table_uc, 0.05 * table_uc) << ev.dump(2);
}

TEST_F(CaseStudyCli, BadCaseFileIsAnErrorNamingTheField) {
  std::ofstream(dir_ / "bad.yaml") << replaced(short_case_, "bar_length_mm: 150", "bar_length_mm: -150");
  const Result r = run("case-study --case " + (dir_ / "bad.yaml").string() + " --out " + (dir_ / "o").string(), dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.yaml:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ldbb.bar_length_mm"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
}

}  // namespace
