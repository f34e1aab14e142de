// Signed errors along the path: the compensated run's deviation along the uncompensated one's, so
// over- and under-compensation are told apart.
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

// A horizontal circle's laps displaced radially by `mm` (outward +), as the synthetic laps are.
TrackerTrace radial_lap(double mm, bool clockwise) {
  return test::circle_lap([mm](double) { return mm; }, clockwise);
}

TEST(SignedError, UnderCompensatedAboveZeroOverCompensatedBelow) {
  // UC pushed outward by 0.5 mm both ways; C still 0.1 mm outward on its clockwise lap (under-
  // compensated) and 0.06 mm inward on its anticlockwise one (over-compensated, past the path).
  PathPlot p = test::synthetic_lap_plot();
  p.uc_laps = {{radial_lap(0.5, true), true}, {radial_lap(0.5, false), false}};
  p.c_laps = {{radial_lap(0.1, true), true}, {radial_lap(-0.06, false), false}};
  const std::string svg = svg_signed_error(p);
  EXPECT_EQ(test::xml_problem(svg), "");
  std::map<std::string, double> mean;
  for (const auto& path : tags(svg, "path")) {
    if (attribute(path, "class") == "signed-error") {
      mean[attribute(path, "data-direction")] = std::stod(attribute(path, "data-mean-mm"));
    }
  }
  ASSERT_EQ(mean.size(), 2u);
  EXPECT_NEAR(mean["cw"], 0.1, 1e-3);
  EXPECT_NEAR(mean["ccw"], -0.06, 1e-3);
  EXPECT_NE(svg.find("C along the UC deflection (mm)"), std::string::npos);
  EXPECT_NE(svg.find("angle about the circle&#39;s centre (deg)"), std::string::npos);
  EXPECT_NE(svg.find("mean +0.100 mm"), std::string::npos);
  EXPECT_NE(svg.find("mean -0.060 mm"), std::string::npos);
  // Where the load pushes inward, inward is + : the sign follows UC's direction, not the radius.
  p.uc_laps = {{radial_lap(-0.5, true), true}, {radial_lap(-0.5, false), false}};
  mean.clear();
  for (const auto& path : tags(svg_signed_error(p), "path")) {
    if (attribute(path, "class") == "signed-error") {
      mean[attribute(path, "data-direction")] = std::stod(attribute(path, "data-mean-mm"));
    }
  }
  EXPECT_NEAR(mean["cw"], -0.1, 1e-3);
  EXPECT_NEAR(mean["ccw"], 0.06, 1e-3);
  // No UC lap to take a direction from: said in the figure, never NaN.
  PathPlot no_uc = test::synthetic_lap_plot();
  no_uc.uc_laps.clear();
  no_uc.uc.clear();
  const std::string none = svg_signed_error(no_uc);
  EXPECT_EQ(test::xml_problem(none), "");
  EXPECT_EQ(none.find("nan"), std::string::npos);
  EXPECT_NE(none.find("no compensated lap with an uncompensated one"), std::string::npos);
}

}  // namespace
}  // namespace deflex
