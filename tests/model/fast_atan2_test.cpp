// The IK's atan2 against std::atan2: random arguments over many magnitudes, the table's split
// points, the axes, signed zeros, infinities and NaN.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "deflex/model/detail/fast_atan2.hpp"

namespace deflex {
namespace {

TEST(FastAtan2, AgreesWithStdAtan2ToAFewUlp) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> exponent(-12.0, 12.0);
  double worst = 0.0;
  for (int i = 0; i < 2000000; ++i) {
    const double y = unit(rng) * std::pow(10.0, exponent(rng));
    const double x = unit(rng) * std::pow(10.0, exponent(rng));
    worst = std::max(worst, std::abs(fast_atan2(y, x) - std::atan2(y, x)));
  }
  EXPECT_LT(worst, 1e-15);
}

TEST(FastAtan2, SplitPointsAxesAndSpecialValues) {
  for (int k = 0; k <= 16; ++k) {
    for (const double eps : {-1e-17, 0.0, 1e-17, 1.0 / 32.0, -1.0 / 32.0}) {
      const double t = k / 16.0 + eps;
      for (const double sx : {1.0, -1.0}) {
        for (const double sy : {1.0, -1.0}) {
          EXPECT_NEAR(fast_atan2(sy * t, sx), std::atan2(sy * t, sx), 1e-15) << t;
          EXPECT_NEAR(fast_atan2(sy, sx * t), std::atan2(sy, sx * t), 1e-15) << t;
        }
      }
    }
  }
  const double inf = std::numeric_limits<double>::infinity();
  for (const double y : {0.0, -0.0, 1.0, -1.0, inf, -inf}) {
    for (const double x : {0.0, -0.0, 1.0, -1.0, inf, -inf}) {
      const double want = std::atan2(y, x);
      const double got = fast_atan2(y, x);
      EXPECT_EQ(got, want) << y << " " << x;
      EXPECT_EQ(std::signbit(got), std::signbit(want)) << y << " " << x;
    }
  }
  EXPECT_TRUE(std::isnan(fast_atan2(std::nan(""), 1.0)));
  EXPECT_TRUE(std::isnan(fast_atan2(1.0, std::nan(""))));
}

}  // namespace
}  // namespace deflex
