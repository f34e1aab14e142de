// The paper's own kind of link (online compensation streamed over TCP every 100 ms) set beside the
// paper's Table 2 wherever ours stand beside the paper's: Figure 5, the parity plot, the tables.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "deflex/report/html_report.hpp"
#include "svg_scan.hpp"
#include "synthetic_study.hpp"
#include "xml_check.hpp"

namespace deflex {
namespace {

using test::attribute;
using test::number;
using test::tags;

const char* const kLinkLabel = "simple message, 100 ms (the paper's kind of link)";

// The synthetic study plus a setup on the paper's own kind of link, compared with the paper's
// Table 2 at its loads: C = 0.3 UC at every load and speed, UC as the online setup's.
StudyResult study_with_paper_link() {
  StudyResult s = test::synthetic_study();
  SetupResult link = s.setups[1];
  link.setup = "online-100ms";
  link.description = "online over simple message";
  link.paper_table = "online";
  link.paper_label = kLinkLabel;
  for (auto& l : link.loads) {
    for (auto& [v, c] : l.c_mm) c = 0.3 * l.uc_mm.at(v);
    for (auto& [v, seeds] : l.c_mm_by_seed) seeds = test::three_seeds(l.c_mm.at(v), 0.1);
    l.fill_compensation();
  }
  s.setups.push_back(link);
  return s;
}

TEST(PaperLink, BesideThePapersBarsInFigure5AndNotBeyondThePaper) {
  const StudyResult s = study_with_paper_link();
  const std::string svg = svg_figure5(s, SetupSelection::kPaper);
  EXPECT_EQ(test::xml_problem(svg), "");
  // offline, online and online-100ms: 3 x 3 loads x 3 speeds C bars, each with the paper's beside
  // it, and 9 UC bars with the paper's UC beside them.
  EXPECT_EQ(test::count_of(svg, "data-value="), 27u);
  EXPECT_EQ(test::count_of(svg, "data-paper="), 27u + 9u);
  std::vector<std::string> labels;
  for (const auto& t : test::texts(svg)) {
    if (attribute(t.tag, "class") != "paper-label") continue;
    std::string text = t.content;
    for (auto k = text.find("&#39;"); k != std::string::npos; k = text.find("&#39;")) text.replace(k, 5, "'");
    labels.push_back(text);
  }
  // The label under the setup's name, on two lines when it is wider than the setup's groups.
  std::string joined;
  for (const auto& l : labels) joined += (joined.empty() ? "" : " ") + l;
  EXPECT_EQ(joined, kLinkLabel);
  // Its 650 N, 10 mm/s bar: the paper's online 0.25 mm beside it, in the same group.
  const auto pos = svg.find("online-100ms 650 N, C at 10 mm/s");
  ASSERT_NE(pos, std::string::npos);
  EXPECT_LT(svg.find(R"(data-paper="0.25")", pos), svg.find("</g>", pos));
  const std::string beyond = svg_figure5(s, SetupSelection::kBeyondPaper);
  EXPECT_EQ(beyond.find("online-100ms"), std::string::npos);
  EXPECT_EQ(test::count_of(beyond, "data-value="), 9u);  // hybrid only
}

TEST(PaperLink, InTheParityPlotAgainstTable2ClearlyMarked) {
  const StudyResult s = study_with_paper_link();
  const std::string svg = svg_parity(s);
  EXPECT_EQ(test::xml_problem(svg), "");
  std::size_t c_points = 0, uc_points = 0;
  for (const auto& c : tags(svg, "circle")) c_points += attribute(c, "data-paper").empty() ? 0 : 1;
  for (const auto& r : tags(svg, "rect")) uc_points += attribute(r, "data-paper").empty() ? 0 : 1;
  EXPECT_EQ(c_points, 18u + 9u);
  EXPECT_EQ(uc_points, 6u + 3u);
  EXPECT_NE(svg.find("online-100ms: against the paper&#39;s Table 2"), std::string::npos);
  EXPECT_NE(svg.find("simple message, 100 ms (the paper&#39;s kind of link)"), std::string::npos);
  // Its 650 N point at 10 mm/s: the paper's 0.25 mm against ours, 0.3 UC at 10 mm/s.
  const double ours = 0.3 * 0.0017 * 650.0 * 1.02;
  bool found = false;
  for (const auto& c : tags(svg, "circle")) {
    if (attribute(c, "data-paper") == "0.25" && std::abs(std::stod(attribute(c, "data-ours")) - ours) < 1e-6) {
      found = true;
    }
  }
  EXPECT_TRUE(found);
  // In the report: its table beside the paper's Table 2, and the captions say why.
  ReportContent r;
  r.study = s;
  const std::string html = html_report(r);
  EXPECT_EQ(test::xml_problem(html), "");
  EXPECT_NE(html.find("Table 4: online-100ms, simple message, 100 ms (the paper&#39;s kind of link), beside the "
                      "paper&#39;s Table 2"),
            std::string::npos);
  EXPECT_NE(html.find("The setup online-100ms, simple message, 100 ms (the paper&#39;s kind of link), is set beside "
                      "the paper's Table 2"),
            std::string::npos);
  // The terminal table too: ours beside the paper's, "0.338 ±0.031 (0.25)" at 650 N and 10 mm/s.
  const std::string text = study_tables_text(s);
  EXPECT_NE(text.find(fmt::format("Table 4 (online-100ms: {}; beside the paper's Table 2)", kLinkLabel)),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(fmt::format("{:.3f} ±", ours)), std::string::npos);
  EXPECT_NE(text.find("(0.25)"), std::string::npos);
}

TEST(PaperLink, TheComparisonSurvivesTheJsonRoundTrip) {
  const StudyResult s = study_with_paper_link();
  const nlohmann::json doc = study_to_json(s);
  EXPECT_EQ(doc.at("setups")[3].at("paper_table"), "online");
  EXPECT_FALSE(doc.at("setups")[0].contains("paper_table"));
  const StudyResult back = study_from_json(doc, "test");
  EXPECT_EQ(back.setups[3].paper_table, "online");
  EXPECT_EQ(back.setups[3].paper_label, kLinkLabel);
  EXPECT_TRUE(back.setups[0].paper_table.empty());
  EXPECT_EQ(study_to_json(back).dump(), doc.dump());
}

}  // namespace
}  // namespace deflex
