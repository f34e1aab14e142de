// Case-study results: the JSON layout of issue 7, the paper's published figures, and the tables.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "deflex/study/study_tables.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

StudyResult example_study() {
  StudyResult s;
  s.speeds_mm_s = {10, 30, 50};
  s.seed = 7;
  SetupResult off{"offline", "force model only", {}};
  LoadResult l125;
  l125.load_N = 125;
  l125.uc_mm = {{10, 0.118}, {30, 0.121}, {50, 0.124}};
  l125.c_mm = {{10, 0.041}, {30, 0.040}, {50, 0.043}};
  l125.fill_compensation();
  off.loads.push_back(l125);
  SetupResult hyb{"hybrid", "", {}};
  LoadResult h;
  h.load_N = 650;
  h.uc_mm = {{10, 1.0}, {30, 1.0}, {50, 1.0}};
  h.c_mm = {{10, 0.1}, {30, 0.1}, {50, 0.1}};
  h.iso_repeatability_mm = {{10, 0.02}};
  h.fill_compensation();
  hyb.loads.push_back(h);
  s.setups = {off, hyb};
  SweepPoint p;
  p.setup = "online";
  p.load_N = 650;
  p.speed_mm_s = 200;
  p.uc_mm = 1.1;
  p.c_mm = 0.4;
  p.compensation = 1.0 - 0.4 / 1.1;
  s.speed_sweep.push_back(p);
  return s;
}

TEST(StudyTables, JsonLayoutOfIssue7) {
  const nlohmann::json doc = study_to_json(example_study());
  ASSERT_TRUE(doc["setups"].is_array());
  ASSERT_EQ(doc["setups"].size(), 2u);
  const auto& off = doc["setups"][0];
  EXPECT_EQ(off["setup"], "offline");
  ASSERT_EQ(off["loads"].size(), 1u);
  const auto& l = off["loads"][0];
  EXPECT_EQ(l["load_N"].get<double>(), 125.0);
  for (const char* key : {"uc_mm", "c_mm", "compensation"}) {
    ASSERT_TRUE(l[key].is_object()) << key;
    EXPECT_EQ(l[key].size(), 3u) << key;
    for (const char* speed : {"10", "30", "50"}) {
      EXPECT_TRUE(l[key].contains(speed)) << key << " " << speed;
    }
  }
  EXPECT_DOUBLE_EQ(l["uc_mm"]["30"].get<double>(), 0.121);
  EXPECT_DOUBLE_EQ(l["c_mm"]["50"].get<double>(), 0.043);
  EXPECT_NEAR(l["compensation"]["10"].get<double>(), 1.0 - 0.041 / 0.118, 1e-15);
  EXPECT_FALSE(l.contains("iso_repeatability_mm"));  // optional maps only when filled
  EXPECT_TRUE(doc["setups"][1]["loads"][0].contains("iso_repeatability_mm"));
  EXPECT_EQ(doc["speed_sweep"][0]["speed_mm_s"].get<double>(), 200.0);
  EXPECT_DOUBLE_EQ(doc["paper"]["online"][2]["uc_mm"].get<double>(), 1.10);
}

TEST(StudyTables, NanIsNullAndJsonRoundTrips) {
  StudyResult s = example_study();
  s.setups[0].loads[0].c_mm[30] = std::nan("");
  s.setups[0].loads[0].fill_compensation();
  const nlohmann::json doc = study_to_json(s);
  EXPECT_TRUE(doc["setups"][0]["loads"][0]["c_mm"]["30"].is_null());
  EXPECT_TRUE(doc["setups"][0]["loads"][0]["compensation"]["30"].is_null());
  const StudyResult back = study_from_json(nlohmann::json::parse(doc.dump()));
  EXPECT_EQ(study_to_json(back).dump(), doc.dump());
}

TEST(StudyTables, MalformedJsonNamesTheField) {
  auto doc = study_to_json(example_study());
  doc["setups"][1]["loads"][0]["uc_mm"]["fast"] = 0.3;
  try {
    study_from_json(doc, "results.json");
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("results.json: setups[1].loads[0].uc_mm"), std::string::npos) << e.what();
  }
  EXPECT_THROW(study_from_json(nlohmann::json::object(), "x"), DataError);
}

TEST(StudyTables, PaperFiguresAgreeWithThePapersProse) {
  // Section 4 of the paper: offline "67% compensation" at every load; online "from 69% to 80%";
  // online UC "approximately doubled" against offline at similar loads. Check the stored tables
  // against those statements (1 - C/UC computed here).
  const PaperFigures p = paper_reference();
  const PaperTable* off = p.table_for("offline");
  const PaperTable* on = p.table_for("online");
  ASSERT_NE(off, nullptr);
  ASSERT_NE(on, nullptr);
  EXPECT_EQ(p.table_for("hybrid"), nullptr);
  ASSERT_EQ(off->rows.size(), 3u);
  ASSERT_EQ(on->rows.size(), 3u);
  for (const auto& r : off->rows) {
    for (const auto& [v, c] : r.c_mm) {
      EXPECT_NEAR(1.0 - c / r.uc_mm, 0.67, 0.02) << r.load_N << " N " << v;
    }
  }
  EXPECT_NEAR(1.0 - on->rows.front().c_mm.at(10) / on->rows.front().uc_mm, 0.69, 0.01);
  EXPECT_NEAR(1.0 - on->rows.back().c_mm.at(30) / on->rows.back().uc_mm, 0.80, 0.04);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_GT(on->rows[i].uc_mm / off->rows[i].uc_mm, 1.6);
  }
  EXPECT_NE(off->row_for(375.4), nullptr);
  EXPECT_EQ(off->row_for(400.0), nullptr);
}

TEST(StudyTables, TextTableShowsOursBesideThePapers) {
  const std::string text = study_tables_text(example_study());
  EXPECT_NE(text.find("Table 1 (offline"), std::string::npos) << text;
  EXPECT_NE(text.find("Table 3 (hybrid, beyond the paper)"), std::string::npos) << text;
  EXPECT_NE(text.find("C1 10 mm/s"), std::string::npos) << text;
  EXPECT_NE(text.find("125 N"), std::string::npos) << text;
  // UC is the mean over speeds (0.121), beside the paper's 0.12; C at 10 mm/s beside 0.04.
  EXPECT_NE(text.find("0.121 (0.12)"), std::string::npos) << text;
  EXPECT_NE(text.find("0.041 (0.04)"), std::string::npos) << text;
  // Compensation: 1 - (mean of the printed C) / printed UC, as the paper's 1 - 0.04/0.12 = 67% is.
  const double ours = 1.0 - (0.041 + 0.040 + 0.043) / 3.0 / 0.121;
  EXPECT_NE(text.find(fmt::format("{:.0f}% (67%)", ours * 100.0)), std::string::npos) << text;
  EXPECT_NE(text.find("125 N +1%"), std::string::npos) << text;  // 0.121 / 0.12 - 1
  EXPECT_NE(text.find("90%"), std::string::npos) << text;        // hybrid, no paper figure
}

TEST(StudyTables, MarkdownAndCsv) {
  const StudyResult s = example_study();
  const std::string md = study_tables_markdown(s);
  EXPECT_NE(md.find("| load | UC mm | C1 10 mm/s | C2 30 mm/s | C3 50 mm/s | compensation % |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("| 125 N | 0.121 (0.12) |"), std::string::npos) << md;
  const auto path = (std::filesystem::temp_directory_path() / "deflex_study.csv").string();
  write_study_csv(s, path);
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 1u + 6u);  // header + 2 setups x 1 load x 3 speeds
  EXPECT_EQ(lines[0].substr(0, 45), "setup,load_N,speed_mm_s,uc_mm,c_mm,compensati");
  EXPECT_EQ(lines[1].substr(0, 32), "offline,125,10,0.118,0.041,0.652");
  EXPECT_NE(lines[1].find(",0.12,0.04"), std::string::npos) << lines[1];  // the paper's UC and C1
  EXPECT_EQ(lines[4].substr(0, 20), "hybrid,650,10,1,0.1,");
  std::filesystem::remove(path);
}

TEST(StudyTables, SpeedColumnsValueLookupAndPercentText) {
  // The given columns win, in the given order; without them every speed any load reports, ascending
  // and once each (the report module lays out its tables and charts by the same function).
  StudyResult s = example_study();
  s.speeds_mm_s = {50, 10};
  EXPECT_EQ(study_speeds_mm_s(s), (std::vector<int>{50, 10}));
  s.speeds_mm_s.clear();
  s.setups[1].loads[0].c_mm[200] = 0.3;
  s.setups[0].loads[0].c_mm[5] = 0.05;
  EXPECT_EQ(study_speeds_mm_s(s), (std::vector<int>{5, 10, 30, 50, 200}));

  EXPECT_DOUBLE_EQ(value_at_speed({{10, 0.5}, {30, 0.25}}, 30), 0.25);
  EXPECT_TRUE(std::isnan(value_at_speed({{10, 0.5}}, 30)));

  EXPECT_EQ(percent_text(0.67), "67%");
  EXPECT_EQ(percent_text(1.0 - 0.4 / 1.1), "64%");  // 63.6% rounds up
  EXPECT_EQ(percent_text(-0.004), "0%");            // rounds to zero: no "-0%"
  EXPECT_EQ(percent_text(-0.25), "-25%");
  EXPECT_EQ(percent_text(std::nan("")), "n/a");
  // Halves away from zero, as a reader rounds them, though the binary quotient falls a hair short:
  // 1 - 0.051 / 0.120 = 57.5% and (0.043 + 0.041 + 0.051) / 0.12 - 1 = +12.5%.
  EXPECT_EQ(percent_text(1.0 - 0.051 / 0.120), "58%");
  EXPECT_EQ(signed_percent_text((0.043 + 0.041 + 0.051) / (0.04 + 0.04 + 0.04) - 1.0), "+13%");
  EXPECT_EQ(signed_percent_text(-0.125), "-13%");
  EXPECT_EQ(signed_percent_text(0.004), "0%");
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

TEST(StudyTables, MeansAndSpreadOverSeedsAndTheirJsonAndCsv) {
  LoadResult l;
  l.load_N = 650;
  l.uc_mm_by_seed = {{10, {1.0, 1.2, 1.1}}, {30, {1.0, 1.0, 1.3}}};
  l.c_mm_by_seed = {{10, {0.1, 0.2, 0.3}}, {30, {0.2, 0.2, 0.2}}};
  l.fill_means();
  EXPECT_DOUBLE_EQ(l.c_mm.at(10), 0.2);
  EXPECT_DOUBLE_EQ(l.uc_mm.at(30), 1.1);
  const Spread c10 = l.c_spread(10);
  EXPECT_EQ(c10.n, 3);
  EXPECT_NEAR(c10.sd, 0.1, 1e-12);  // sample standard deviation of 0.1, 0.2, 0.3
  EXPECT_DOUBLE_EQ(c10.min, 0.1);
  EXPECT_DOUBLE_EQ(c10.max, 0.3);
  // UC per seed is averaged over the speeds first: 1.0, 1.1, 1.2 -> mean 1.1, sd 0.1.
  EXPECT_NEAR(l.uc_mean_spread().mean, 1.1, 1e-12);
  EXPECT_NEAR(l.uc_mean_spread().sd, 0.1, 1e-12);
  // Compensation per seed: mean over the speeds of 1 - C/UC, written out here.
  const double s0 = ((1 - 0.1 / 1.0) + (1 - 0.2 / 1.0)) / 2, s1 = ((1 - 0.2 / 1.2) + (1 - 0.2 / 1.0)) / 2,
               s2 = ((1 - 0.3 / 1.1) + (1 - 0.2 / 1.3)) / 2;
  EXPECT_NEAR(l.compensation_spread().mean, (s0 + s1 + s2) / 3, 1e-12);
  EXPECT_EQ(l.seeds(), 3);

  StudyResult study;
  study.seeds = {1, 2, 3};
  SetupResult on{"online", "", {l}};
  study.setups = {on};
  study.speeds_mm_s = {10, 30};
  ErrorBudget b;
  b.setup = "online";
  b.load_N = 650;
  b.speed_mm_s = 50;
  b.residual_mm_all = 0.2;
  b.uc_mm = 1.1;
  b.seed = 7;
  b.laps = 6;
  b.entries = {{"lost motion", "40 urad", 0.15, one_at_a_time_sensitivity(0.2, 0.15)}};
  b.residual_mm_all_off = 0.04;
  study.error_budgets = {b};
  const StudyResult back = study_from_json(study_to_json(study), "test");
  EXPECT_EQ(back.seeds, study.seeds);
  EXPECT_EQ(back.setups[0].loads[0].c_mm_by_seed, l.c_mm_by_seed);
  ASSERT_EQ(back.error_budgets.size(), 1u);
  EXPECT_EQ(back.error_budgets[0].entries[0].effect, "lost motion");
  EXPECT_EQ(back.error_budgets[0].seed, 7u);
  EXPECT_EQ(back.error_budgets[0].laps, 6);
  EXPECT_NEAR(back.error_budgets[0].entries[0].sensitivity, 0.25, 1e-12);
  EXPECT_EQ(back.error_budgets[0].residual_mm_all_off, 0.04);
  // Not run: null in the JSON, NaN again when read back.
  StudyResult not_run = study;
  not_run.error_budgets[0].residual_mm_all_off = std::nan("");
  const nlohmann::json not_run_json = study_to_json(not_run);
  EXPECT_TRUE(not_run_json.at("error_budget")[0].at("residual_mm_all_off").is_null());
  EXPECT_TRUE(std::isnan(study_from_json(not_run_json, "test").error_budgets[0].residual_mm_all_off));
  // The text table carries the spread: "0.200 ±0.100 (0.25)" for C at 10 mm/s.
  const std::string text = study_tables_text(study);
  EXPECT_NE(text.find("0.200 ±0.100 (0.25)"), std::string::npos) << text;
  EXPECT_NE(text.find("1.100 ±0.100 (1.10)"), std::string::npos) << text;
  const std::string dir = ::testing::TempDir();
  write_error_budget_csv(study, dir + "/budget.csv");
  std::ifstream in(dir + "/budget.csv");
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_EQ(header,
            "setup,load_N,speed_mm_s,seed,laps,residual_mm_all,residual_mm_all_off,uc_mm,effect,size,"
            "residual_mm_without_it,sensitivity_one_at_a_time");
  EXPECT_EQ(row, "online,650,50,7,6,0.2,0.04,1.1,lost motion,40 urad,0.15,0.25");
}

}  // namespace
}  // namespace deflex
