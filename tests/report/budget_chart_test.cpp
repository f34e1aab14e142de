// The error budget named and drawn as what it is: a one-effect-at-a-time sensitivity beside C with
// every effect on and with every effect off at once.
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

TEST(ErrorBudgetChart, OneBarPerEffectAndTheTwoReferences) {
  ErrorBudget b;
  b.setup = "online";
  b.load_N = 650;
  b.speed_mm_s = 50;
  b.residual_mm_all = 0.20;
  b.residual_mm_all_off = 0.05;
  b.uc_mm = 1.1;
  b.entries = {{"lost motion", "25 urad", 0.17, one_at_a_time_sensitivity(0.20, 0.17)},
               {"sensor compliance", "0.35 um/N", 0.12, one_at_a_time_sensitivity(0.20, 0.12)},
               {"servo", "8 ms", 0.23, one_at_a_time_sensitivity(0.20, 0.23)}};
  const std::string svg = svg_error_budget(b);
  EXPECT_EQ(test::xml_problem(svg), "");
  std::vector<std::string> bars;
  for (const auto& r : tags(svg, "rect")) {
    if (attribute(r, "class") == "budget-bar") bars.push_back(r);
  }
  ASSERT_EQ(bars.size(), 3u);
  // Largest drop first: 0.12, 0.17, 0.23 from the top; every bar's length in proportion to its C.
  EXPECT_EQ(attribute(bars[0], "data-value"), "0.12");
  EXPECT_EQ(attribute(bars[2], "data-value"), "0.23");
  EXPECT_LT(number(bars[0], "y"), number(bars[1], "y"));
  const double x0 = number(bars[0], "x");
  const double px_per_mm = number(bars[0], "width") / 0.12;
  EXPECT_NEAR(number(bars[2], "width"), 0.23 * px_per_mm, 0.02);
  EXPECT_NE(attribute(bars[2], "fill"), attribute(bars[0], "fill")) << "C rising with the effect off stands out";
  // The references at C with every effect (0.20) and with every effect off (0.05), same scale.
  for (const auto& [cls, mm] : {std::pair{"ref-all-on", 0.20}, std::pair{"ref-all-off", 0.05}}) {
    bool found = false;
    for (const auto& l : tags(svg, "line")) {
      if (attribute(l, "class") != cls) continue;
      found = true;
      EXPECT_NEAR(number(l, "x1"), x0 + mm * px_per_mm, 0.02) << cls;
    }
    EXPECT_TRUE(found) << cls;
  }
  // Each bar's value and its sensitivity as printed: (0.200 - 0.120) / 0.200 = 40%, (0.2 - 0.23) / 0.2 = -15%.
  EXPECT_NE(svg.find("0.120 mm (40%)"), std::string::npos);
  EXPECT_NE(svg.find("0.230 mm (-15%)"), std::string::npos);
  EXPECT_NE(svg.find("(mm)"), std::string::npos);
}

TEST(ErrorBudgetChart, TheReportCallsItASensitivityAndSaysWhatItAddsUpTo) {
  const ReportContent r = test::synthetic_report();
  const std::string html = html_report(r);
  EXPECT_EQ(test::xml_problem(html), "");
  EXPECT_NE(html.find("Error budget: one effect at a time"), std::string::npos);
  EXPECT_NE(html.find("It is not a share of the residual"), std::string::npos);
  EXPECT_EQ(html.find("<th>share of the residual"), std::string::npos);
  // The synthetic budget: C 0.20 with every effect; without each 0.12, 0.17, 0.195, 0.2004 (printed
  // 0.200): 40% + 15% + 3% (2.5% printed as 0.195 -> (0.200 - 0.195) / 0.200 = 2.5% -> 3%) + 0%.
  EXPECT_NE(html.find("The 4 sensitivities above add up to 58%, while switching every effect off at once lowers C by "
                      "75%"),
            std::string::npos);
  EXPECT_NE(html.find("<td>0.050</td><td>75%</td>"), std::string::npos) << "the every-effect-off row";
  // The CSV names the column for what it is.
  const std::string csv = error_budget_csv_text(r.study);
  EXPECT_NE(csv.find("sensitivity_one_at_a_time"), std::string::npos);
  EXPECT_EQ(csv.find("share"), std::string::npos);
  EXPECT_NE(csv.find(",0.2,0.05,1.1,"), std::string::npos) << csv;
}

}  // namespace
}  // namespace deflex
