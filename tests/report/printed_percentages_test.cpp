// Every percentage printed beside figures is the one a reader computes from those printed figures.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deflex/report/html_report.hpp"
#include "svg_scan.hpp"
#include "synthetic_study.hpp"
#include "xml_check.hpp"

namespace deflex {
namespace {

using test::attribute;
using test::number;
using test::tags;

// The numbers of a text with the HTML tags taken out, in order; "(0.12)" and "67%" are kept as written.
std::vector<std::string> tokens(std::string text) {
  std::string plain;
  bool in_tag = false;
  for (const char ch : text) {
    if (ch == '<') in_tag = true;
    if (!in_tag) plain += ch;
    if (ch == '>') {
      in_tag = false;
      plain += ' ';
    }
  }
  std::istringstream in(plain);
  std::vector<std::string> out;
  for (std::string t; in >> t;) out.push_back(t);
  return out;
}

int reader_percent(double fraction) { return static_cast<int>(std::lround(fraction * 100.0)); }

// Offline 125 N with figures whose unrounded percentages differ from the printed ones: UC 0.1184,
// 0.1213, 0.1241 (mean 0.12127, printed 0.121); C 0.04776 at every speed (printed 0.048).
// Unrounded: compensation 1 - 0.04776/0.12127 = 61%, C vs the paper's 0.04 +19%; from the printed
// figures: 1 - 0.048/0.121 = 60% and 0.048/0.04 = +20%.
StudyResult study_with_rounding() {
  StudyResult s;
  s.seed = 1;
  s.speeds_mm_s = {10, 30, 50};
  LoadResult l;
  l.load_N = 125;
  l.uc_mm = {{10, 0.1184}, {30, 0.1213}, {50, 0.1241}};
  l.c_mm = {{10, 0.04776}, {30, 0.04776}, {50, 0.04776}};
  l.fill_compensation();
  s.setups.push_back({"offline", "", {l}});
  return s;
}

TEST(PrintedPercentages, TheTerminalTableRecomputesFromItsOwnPrintedFigures) {
  const std::string text = study_tables_text(study_with_rounding());
  std::istringstream in(text);
  std::string row, uc_line;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("  125 N", 0) == 0) row = line;
    if (line.find("UC against the paper's") != std::string::npos) uc_line = line;
  }
  ASSERT_FALSE(row.empty()) << text;
  // "125 N  0.121 (0.12)  0.048 (0.04)  0.048 (0.04)  0.048 (0.04)  60% (67%)"
  const std::vector<std::string> t = tokens(row);
  ASSERT_EQ(t.size(), 12u) << row;
  const double uc = std::stod(t[2]);
  const double c = (std::stod(t[4]) + std::stod(t[6]) + std::stod(t[8])) / 3.0;
  EXPECT_EQ(t[2], "0.121");
  EXPECT_EQ(t[4], "0.048");
  EXPECT_EQ(t[10], fmt::format("{}%", reader_percent(1.0 - c / uc)));
  EXPECT_EQ(t[10], "60%");
  // "UC against the paper's: 125 N +1%": 0.121 / 0.12.
  EXPECT_NE(uc_line.find(fmt::format("125 N +{}%", reader_percent(uc / 0.12 - 1.0))), std::string::npos) << uc_line;
}

TEST(PrintedPercentages, TheHtmlRowRecomputesFromItsOwnPrintedFigures) {
  ReportContent r;
  r.study = study_with_rounding();
  const std::string html = html_report(r);
  const auto start = html.find("<tr><td class=\"l\">125 N</td>");
  ASSERT_NE(start, std::string::npos);
  const std::vector<std::string> t = tokens(html.substr(start, html.find("</tr>", start) - start));
  // 125 N | UC (paper) | C1 (paper) C2 (paper) C3 (paper) | comp. per speed (paper's) x 3 | UC vs | C vs
  ASSERT_EQ(t.size(), 2u + 2u + 6u + 6u + 2u) << html.substr(start, 600);
  const double uc = std::stod(t[2]);
  const double c1 = std::stod(t[4]), c2 = std::stod(t[6]), c3 = std::stod(t[8]);
  const double paper_c = std::stod(t[5].substr(1)) + std::stod(t[7].substr(1)) + std::stod(t[9].substr(1));
  // Each speed's compensation from the printed UC and C beside it.
  EXPECT_EQ(t[10], fmt::format("{}%", reader_percent(1.0 - c1 / uc)));
  EXPECT_EQ(t[12], fmt::format("{}%", reader_percent(1.0 - c2 / uc)));
  // UC and C against the paper's, from the printed figures: +1% and +20% (unrounded: +19%).
  EXPECT_EQ(t[16], fmt::format("{:+}%", reader_percent(uc / std::stod(t[3].substr(1)) - 1.0)));
  EXPECT_EQ(t[17], fmt::format("{:+}%", reader_percent((c1 + c2 + c3) / paper_c - 1.0)));
  EXPECT_EQ(t[17], "+20%");
  // The compensation table prints the same figure as the results table.
  const auto comp = html.find("<tr><td class=\"l\">offline</td><td>125 N</td>");
  ASSERT_NE(comp, std::string::npos);
  EXPECT_EQ(tokens(html.substr(comp, html.find("</tr>", comp) - comp))[3], "60%");
}

}  // namespace
}  // namespace deflex
