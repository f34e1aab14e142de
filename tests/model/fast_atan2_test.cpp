// The IK's atan2 against std::atan2: random arguments over many magnitudes, the table's split
// points, the axes, signed zeros, infinities and NaN; and its angle of a unit vector against
// std::atan2 on unit vectors, their table points, axes, signed zeros and NaN.
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

TEST(UnitVectorAngle, AgreesWithStdAtan2ToAFewUlpOnUnitVectors) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> angle(-4.0, 4.0);
  double worst = 0.0;
  for (int i = 0; i < 2000000; ++i) {
    const double a = angle(rng);
    const double s = std::sin(a);
    const double c = std::cos(a);
    worst = std::max(worst, std::abs(unit_vector_angle(s, c) - std::atan2(s, c)));
  }
  EXPECT_LT(worst, 1e-15);
}

TEST(UnitVectorAngle, TablePointsAxesAndSpecialValues) {
  // Sines at the table's points k/64 and half-way between them, in every octant.
  for (int k = 0; k <= 46; ++k) {
    for (const double eps : {-1e-17, 0.0, 1e-17, 1.0 / 128.0}) {
      const double x = k / 64.0 + eps;
      if (x < 0.0 || x > std::sqrt(0.5)) {
        continue;
      }
      const double y = std::sqrt(1.0 - x * x);
      for (const double sx : {1.0, -1.0}) {
        for (const double sy : {1.0, -1.0}) {
          EXPECT_NEAR(unit_vector_angle(sy * x, sx * y), std::atan2(sy * x, sx * y), 1e-15) << x;
          EXPECT_NEAR(unit_vector_angle(sy * y, sx * x), std::atan2(sy * y, sx * x), 1e-15) << x;
        }
      }
    }
  }
  for (const double s : {0.0, -0.0, 1.0, -1.0}) {
    for (const double c : {0.0, -0.0, 1.0, -1.0}) {
      if (std::abs(s) + std::abs(c) != 1.0) {
        continue;
      }
      EXPECT_EQ(unit_vector_angle(s, c), std::atan2(s, c)) << s << " " << c;
      EXPECT_EQ(std::signbit(unit_vector_angle(s, c)), std::signbit(std::atan2(s, c))) << s << " " << c;
    }
  }
  // A slightly long or short vector (as a rotation's entries are) moves the angle by almost nothing.
  EXPECT_NEAR(unit_vector_angle(0.6 * (1.0 + 1e-12), 0.8 * (1.0 + 1e-12)), std::atan2(0.6, 0.8), 1e-14);
  EXPECT_TRUE(std::isnan(unit_vector_angle(std::nan(""), 1.0)));
  EXPECT_TRUE(std::isnan(unit_vector_angle(0.5, std::nan(""))));
  // Far from unit length: std::atan2's answer (through fast_atan2).
  EXPECT_NEAR(unit_vector_angle(3.0, -4.0), std::atan2(3.0, -4.0), 1e-15);
}

}  // namespace
}  // namespace deflex
