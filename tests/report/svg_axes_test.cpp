// Axis ticks of the report's charts: round steps (1, 2, 5 x 10^k), ticks at exact multiples of the
// step, and ranges too narrow for the doubles at their magnitude still end.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/report/detail/svg_canvas.hpp"

namespace deflex {
namespace {

TEST(NiceTicks, RoundStepsAtExactMultiples) {
  // 0..1 in about 6: raw step 1/6 -> 0.2.
  const std::vector<double> a = svg::nice_ticks(0.0, 1.0, 6);
  ASSERT_EQ(a.size(), 6u);
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k], static_cast<double>(k) * 0.2) << k;
  }
  // 0.3..0.7 in about 4: raw step 0.1 -> 0.1; ticks 3 x 0.1 .. 7 x 0.1, each the product, no drift
  // from adding 0.1 up (0.3 + 0.1 + 0.1 is 0.5000000000000001).
  const std::vector<double> b = svg::nice_ticks(0.3, 0.7, 4);
  ASSERT_EQ(b.size(), 5u);
  for (std::size_t k = 0; k < b.size(); ++k) {
    EXPECT_EQ(b[k], static_cast<double>(3 + k) * 0.1) << k;
  }
  // -12..37 in about 5: raw 9.8 -> 10; ticks -10, 0, 10, 20, 30, with zero exactly zero.
  EXPECT_EQ(svg::nice_ticks(-12.0, 37.0, 5), (std::vector<double>{-10.0, 0.0, 10.0, 20.0, 30.0}));
  // No range: the one value.
  EXPECT_EQ(svg::nice_ticks(2.0, 2.0, 6), (std::vector<double>{2.0}));
}

TEST(NiceTicks, RangeBelowTheDoublesResolutionEnds) {
  // hi is the next double after 1000: the step (~2e-14) is below half an ulp of 1000 (~5.7e-14), so
  // adding it never moved t and the old loop pushed ticks until memory ran out.
  const double lo = 1000.0;
  const double hi = std::nextafter(lo, 2000.0);
  const std::vector<double> t = svg::nice_ticks(lo, hi, 6);
  ASSERT_FALSE(t.empty());
  EXPECT_LE(t.size(), 2u);
  for (const double v : t) {
    EXPECT_GE(v, lo - 1e-12);
    EXPECT_LE(v, hi + 1e-12);
  }
}

TEST(NiceCeiling, NextRoundValueAtOrAbove) {
  EXPECT_DOUBLE_EQ(svg::nice_ceiling(0.73), 0.8);
  EXPECT_DOUBLE_EQ(svg::nice_ceiling(1.0), 1.0);
  EXPECT_DOUBLE_EQ(svg::nice_ceiling(101.0), 120.0);
  EXPECT_DOUBLE_EQ(svg::nice_ceiling(0.0021), 0.0025);
  EXPECT_EQ(svg::nice_ceiling(0.0), 1.0);
  EXPECT_EQ(svg::nice_ceiling(std::nan("")), 1.0);
}

}  // namespace
}  // namespace deflex
