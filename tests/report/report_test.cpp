// The report's charts and HTML: well-formed, self-contained, and drawing what they claim (bar
// heights proportional to the values, magnified deviations at the stated factor).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "deflex/model/tracker_trace.hpp"
#include "deflex/report/html_report.hpp"
#include "deflex/text/errors.hpp"
#include "svg_scan.hpp"
#include "synthetic_study.hpp"
#include "xml_check.hpp"

namespace deflex {
namespace {

TEST(XmlCheck, CatchesMalformedDocuments) {
  EXPECT_EQ(test::xml_problem("<a x=\"1\"><b/>t &amp; u</a>"), "");
  EXPECT_NE(test::xml_problem("<a><b></a></b>"), "");
  EXPECT_NE(test::xml_problem("<a>"), "");
  EXPECT_NE(test::xml_problem("<a>x < y</a>"), "");
  EXPECT_NE(test::xml_problem("<a>fish & chips</a>"), "");
  EXPECT_NE(test::xml_problem("<a x=\"1>"), "");
  EXPECT_NE(test::xml_problem("<a>1 > 0</a>"), "");
}

using test::attribute;

// (value, height) of every bar carrying a data-value. Plain scanning, not std::regex: libstdc++'s
// regex recurses per character and overflows the stack on a long SVG under AddressSanitizer.
std::vector<std::pair<double, double>> bars(const std::string& svg) {
  std::vector<std::pair<double, double>> out;
  for (auto p = svg.find("<rect "); p != std::string::npos; p = svg.find("<rect ", p + 1)) {
    const std::string tag = svg.substr(p, svg.find('>', p) - p);
    const std::string height = attribute(tag, "height");
    const std::string value = attribute(tag, "data-value");
    if (!height.empty() && !value.empty() && tag.find(" height=") < tag.find(" data-value=")) {
      out.emplace_back(std::stod(value), std::stod(height));
    }
  }
  return out;
}

TEST(Figure5, OneBarPerSetupLoadAndSpeedScaledToItsValue) {
  const StudyResult s = test::synthetic_study();
  const std::string svg = svg_figure5(s, SetupSelection::kAll);
  EXPECT_EQ(test::xml_problem(svg), "");
  const auto b = bars(svg);
  ASSERT_EQ(b.size(), 27u);  // 3 setups x 3 loads x 3 speeds
  // Scale from the tallest bar (least rounding), then every bar must follow it.
  const auto tallest = *std::max_element(b.begin(), b.end(), [](auto x, auto y) { return x.second < y.second; });
  const double px_per_mm = tallest.second / tallest.first;
  for (const auto& [v, h] : b) {
    EXPECT_NEAR(h, v * px_per_mm, 0.012) << v;  // heights are written with 2 decimals
  }
  EXPECT_NEAR(b[0].first, s.setups[0].loads[0].c_mm.at(10), 1e-4);
  // The paper's values beside ours, as outlined bars: C of the offline and online setups (18) and
  // their UC (6); the hybrid setup has none.
  EXPECT_EQ(test::count_of(svg, "data-paper="), 24u);
  EXPECT_NE(svg.find("offline (OFF)"), std::string::npos);
  EXPECT_NE(svg.find("online (ON)"), std::string::npos);
  EXPECT_NE(svg.find("(mm)"), std::string::npos);  // the axis says its unit
  // 625 N offline: UC = 0.00098 * 625 * (1 + 0.002 v), mean over 10, 30, 50 mm/s = 0.6125 * 1.06 = 0.649.
  EXPECT_NE(svg.find(R"(data-uc="0.64925")"), std::string::npos) << "625 N offline UC, the mean over the speeds";
}

TEST(Figure5, EmptyStudyStillDraws) {
  const std::string svg = svg_figure5(StudyResult{}, SetupSelection::kAll);
  EXPECT_EQ(test::xml_problem(svg), "");
  EXPECT_NE(svg.find("no results"), std::string::npos);
}

// Points of the n-th polyline drawn in `colour` (plain scanning, see bars()).
std::vector<std::pair<double, double>> polyline_points(const std::string& svg, const std::string& colour, int n) {
  const std::string open = "<polyline points=\"";
  const std::string tail = "\" fill=\"none\" stroke=\"" + colour + "\"";
  int k = 0;
  for (auto p = svg.find(open); p != std::string::npos; p = svg.find(open, p + 1)) {
    const auto start = p + open.size();
    const auto end = svg.find('"', start);
    if (svg.compare(end, tail.size(), tail) != 0 || k++ != n) {
      continue;
    }
    std::vector<std::pair<double, double>> pts;
    std::stringstream ss(svg.substr(start, end - start));
    std::string pair;
    while (ss >> pair) {
      const auto comma = pair.find(',');
      pts.emplace_back(std::stod(pair.substr(0, comma)), std::stod(pair.substr(comma + 1)));
    }
    return pts;
  }
  return {};
}

double mean_radius(const std::vector<std::pair<double, double>>& pts, double cx, double cy) {
  double r = 0.0;
  for (const auto& [x, y] : pts) {
    r += std::hypot(x - cx, y - cy);
  }
  return r / static_cast<double>(pts.size());
}

TEST(PathPlot, DeviationsAreMagnifiedByTheStatedFactor) {
  // Unloaded: a circle of 100 mm in a tilted plane; UC: radius + 0.5 mm; C: radius + 0.1 mm. With
  // magnification 40 the drawn UC circle has radius 100 + 40 * 0.5 = 120 mm against the unloaded
  // one's 100 mm, C 104 mm, whatever the pixel scale.
  const Eigen::AngleAxisd tilt(0.4, Vector3(0.3, 1.0, 0.0).normalized());
  const Vector3 centre(1.5, 0.2, 0.9);
  auto circle = [&](double r) {
    TrackerTrace t;
    for (int i = 0; i <= 3000; ++i) {
      const double a = 2.0 * kPi * i / 3000;
      t.push_back({i * 1e-3, centre + tilt * Vector3(r * std::cos(a), r * std::sin(a), 0.0)});
    }
    return t;
  };
  PathPlot p{"test", circle(0.1), circle(0.1005), circle(0.1001), 40.0, {}, {}, {}};
  const std::string svg = svg_path_plot(p);
  EXPECT_EQ(test::xml_problem(svg), "");
  EXPECT_NE(svg.find("magnified x40"), std::string::npos);
  // The first polyline of each colour is the left panel's (legend swatches are lines).
  const auto unloaded = polyline_points(svg, "#888888", 0);
  const auto uc = polyline_points(svg, "#D62728", 0);
  const auto c = polyline_points(svg, "#1F77B4", 0);
  ASSERT_GT(unloaded.size(), 100u);
  ASSERT_GT(uc.size(), 100u);
  ASSERT_GT(c.size(), 100u);
  double cx = 0.0, cy = 0.0;
  for (const auto& [x, y] : unloaded) {
    cx += x;
    cy += y;
  }
  cx /= static_cast<double>(unloaded.size());
  cy /= static_cast<double>(unloaded.size());
  const double r0 = mean_radius(unloaded, cx, cy);
  EXPECT_NEAR(mean_radius(uc, cx, cy) / r0, 1.20, 0.005);
  EXPECT_NEAR(mean_radius(c, cx, cy) / r0, 1.04, 0.005);
  // Legend: the mean deviations of the last laps at true scale, and which way they ran (the circle
  // turns anticlockwise seen from the side its normal points to).
  EXPECT_NE(svg.find("UC, last lap, anticlockwise: mean 0.500 mm"), std::string::npos);
  EXPECT_NE(svg.find("C, last lap, anticlockwise: mean 0.100 mm"), std::string::npos);
}

TEST(PathPlot, AutomaticMagnificationAndBadInput) {
  // Largest deviation 1.0 mm on a path 200 mm across: 12% of 200 / 1.0 = 24 -> the nice factor 20.
  PathPlot p = test::synthetic_path_plot(1.0, 0.2, 5);
  double max_dev = 0.0;
  for (std::size_t i = 0; i < p.uc.size(); ++i) {
    max_dev = std::max(max_dev, (p.uc[i].p_m - p.unloaded[i].p_m).norm());
  }
  ASSERT_LT(max_dev, 1.01e-3);  // the synthetic field's largest UC deviation (test's own check)
  const std::string svg = svg_path_plot(p);
  EXPECT_EQ(test::xml_problem(svg), "");
  EXPECT_NE(svg.find("magnified x20"), std::string::npos);
  PathPlot only_unloaded{"no loaded runs", p.unloaded, {}, {}, 0.0, {}, {}, {}};
  const std::string empty = svg_path_plot(only_unloaded);
  EXPECT_EQ(test::xml_problem(empty), "");
  EXPECT_NE(empty.find("UC (no data)"), std::string::npos);
  EXPECT_EQ(empty.find("nan"), std::string::npos);
  // Too little to draw is said in the figure, not thrown: one bad plot must not lose a whole report.
  PathPlot one_sample{"one sample", {p.unloaded.front()}, p.uc, p.c, 0.0, {}, {}, {}};
  const std::string none = svg_path_plot(one_sample);
  EXPECT_EQ(test::xml_problem(none), "");
  EXPECT_NE(none.find("no unloaded path"), std::string::npos);
}

TEST(SpeedSweep, OneLinePerSeriesInBothPanels) {
  const std::string svg = svg_speed_sweep(test::synthetic_study());
  EXPECT_EQ(test::xml_problem(svg), "");
  EXPECT_NE(svg.find("online 650 N"), std::string::npos);
  EXPECT_NE(svg.find("online-latency-comp 650 N"), std::string::npos);
  EXPECT_NE(svg.find("TCP speed (mm/s)"), std::string::npos);
  // 2 series x 6 speeds in each of 4 panels: compensation, C, C time-synchronous, UC.
  EXPECT_EQ(test::count_of(svg, "<circle "), 48u + 2u) << "points and the 2 legend swatches";
  EXPECT_EQ(test::count_of(svg, R"(<circle cx)") - 2u, test::count_of(svg, "data-value="));
  EXPECT_EQ(test::xml_problem(svg_speed_sweep(StudyResult{})), "");
}

TEST(HtmlReport, SelfContainedWellFormedAndComplete) {
  const ReportContent content = test::synthetic_report();
  const std::string html = html_report(content);
  EXPECT_EQ(test::xml_problem(html), "");
  for (const char* needle :
       {"Table 1: offline compensation", "Table 2: online compensation", "Table 3: hybrid (beyond the paper)",
        "Figure 5", "ISO 9283", "Error budget", "Speed sweep", "Paths, laps and directions", "Notes",
        "force sensor compliance &lt;unmodelled&gt;", "Compensation per load", "Trends against load",
        "Parity with the paper", "Time-synchronous error beside", "LDBB loads 125-650 N &amp; speeds",
        "<span class=\"paper\">(0.12)</span>", "<span class=\"paper\">(1.10)</span>"}) {
    EXPECT_NE(html.find(needle), std::string::npos) << needle;
  }
  // Figure 5 (the paper's setups), its companion (hybrid), compensation, trends, parity, for the one path
  // plot its path, polar, per-lap and signed-error figures, the budget's chart and the sweep.
  EXPECT_EQ(test::count_of(html, "<svg "), 11u);
  // Budget sensitivities: (0.20 - 0.12) / 0.20 = 40%; 0.2004 prints as 0.200, so 0%, never "-0%".
  EXPECT_NE(html.find("<td>0.120</td><td>40%</td>"), std::string::npos);
  // Tables give the spread over the seeds: 625 N offline, C at 10 mm/s: mean m = 0.6125 * 1.02 *
  // 0.34 = 0.21242, seeds m * (0.88, 1.024, 1.096): sample sd 0.12 m sqrt(0.84) = 0.0234.
  EXPECT_NE(html.find("0.212 <span class=\"sd\">&#177;0.023</span> <span class=\"paper\">(0.21)</span>"),
            std::string::npos);
  EXPECT_NE(html.find("<td>0.200</td><td>0%</td>"), std::string::npos);
  EXPECT_EQ(html.find("-0%"), std::string::npos);
  // Nothing to fetch: no scripts, no external resources.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("src="), std::string::npos);
  EXPECT_EQ(html.find("href="), std::string::npos);
  EXPECT_EQ(html.find("@import"), std::string::npos);
  EXPECT_EQ(test::count_of(html, "http"), test::count_of(html, "xmlns=\"http://www.w3.org/2000/svg\""));
}

TEST(HtmlReport, TheControllerLinksTableHasARowPerLinkWithItsCompensation) {
  ReportContent content = test::synthetic_report();
  EXPECT_EQ(html_report(content).find("id=\"links\""), std::string::npos);  // no links, no table
  study::LinkSummary l;
  l.setup = "online-fanuc";
  l.link = "fanuc-j519";
  l.cycles = 491008;
  l.rejected = 2;
  l.guard_trips = 0;
  l.max_command_deviation_rad = 1.618e-3;
  l.bound_rad = 0.01;
  l.max_tcp_correction_m = 1.442e-3;
  l.measured_delay_s = 0.061;
  l.load_n = 650;
  l.uc_mm = 1.051;
  l.c_mm = 0.142;
  l.compensation = 1.0 - 0.142 / 1.051;  // 86.5 %: prints 86%, halves away from zero
  l.controller_note = "peak jerk 40 % of the controller's limit <J519>";
  study::LinkSummary rsi = l;
  rsi.setup = "online-rsi";
  rsi.link = "rsi";
  rsi.measured_delay_s = NAN;  // a link that measured no delay
  content.links = {l, rsi};
  const std::string html = html_report(content);
  EXPECT_EQ(test::xml_problem(html), "");
  EXPECT_NE(html.find("<h2 id=\"links\">Controller links</h2>"), std::string::npos);
  EXPECT_NE(html.find("<tr><td class=\"l\">online-fanuc</td><td class=\"l\">fanuc-j519</td><td>491008</td><td>2</td>"
                      "<td>0</td><td>1.618</td><td>10.0</td><td>1.442</td><td>61</td><td>650 N</td><td>1.051</td>"
                      "<td>0.142</td><td>86%</td><td class=\"l\">peak jerk 40 % of the controller&#39;s limit "
                      "&lt;J519&gt;</td></tr>"),
            std::string::npos);
  EXPECT_NE(html.find("<td>1.442</td><td>n/a</td>"), std::string::npos);
}

TEST(HtmlReport, WritesTheReportAndFigures) {
  // DEFLEX_REPORT_EXAMPLE_DIR keeps the example (to look at it in a browser); otherwise a temp dir.
  const char* keep = std::getenv("DEFLEX_REPORT_EXAMPLE_DIR");
  const std::filesystem::path dir =
      keep != nullptr ? std::filesystem::path(keep) : std::filesystem::temp_directory_path() / "deflex_report_test";
  const ReportContent content = test::synthetic_report();
  write_report(content, dir.string());
  for (const char* f : {"report.html", "figure5.svg", "figure5_beyond.svg", "compensation.svg", "trends.svg",
                        "parity.svg", "speed_sweep.svg", "path_1.svg", "polar_1.svg", "laps_1.svg", "signed_1.svg",
                        "budget_1.svg", "tables.md", "tables.csv", "error_budget.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  }
  std::ifstream in(dir / "report.html");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), html_report(content));
  if (keep == nullptr) {
    std::filesystem::remove_all(dir);
  }
  // A path that cannot be a directory is a clear error.
  EXPECT_THROW(write_report(content, "/proc/deflex-cannot-write-here"), Error);
}

TEST(ErrorBudget, OneAtATimeSensitivity) {
  EXPECT_NEAR(one_at_a_time_sensitivity(0.20, 0.12), 0.4, 1e-15);
  EXPECT_NEAR(one_at_a_time_sensitivity(0.20, 0.25), -0.25, 1e-15);  // switching it off made things worse
  EXPECT_TRUE(std::isnan(one_at_a_time_sensitivity(0.0, 0.1)));
}

}  // namespace
}  // namespace deflex
