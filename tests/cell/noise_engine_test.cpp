// The cell's noise engine: its reference mode is the Mersenne Twister draw for draw, and its fast
// mode gives standard normal draws (through the same ziggurat) with the moments and tails of the
// normal distribution.
#include "deflex/cell/noise_engine.hpp"

#include <gtest/gtest.h>

#include <boost/random/normal_distribution.hpp>
#include <cmath>
#include <random>

namespace deflex::cell {
namespace {

TEST(NoiseEngine, TheReferenceModeIsTheMersenneTwister) {
  NoiseEngine engine(12345, false);
  std::mt19937_64 mt(12345);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(engine(), mt()) << i;
  engine.reseed(7, false);
  mt.seed(7);
  for (int i = 0; i < 10; ++i) ASSERT_EQ(engine(), mt()) << i;
}

TEST(NoiseEngine, TheFastModeGivesStandardNormalDraws) {
  NoiseEngine engine(99, true);
  boost::random::normal_distribution<double> normal(0.0, 1.0);
  constexpr int kDraws = 1000000;
  double sum = 0.0, sum2 = 0.0, sum4 = 0.0;
  int beyond_2 = 0;
  for (int i = 0; i < kDraws; ++i) {
    const double x = normal(engine);
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    if (std::abs(x) > 2.0) ++beyond_2;
  }
  const double n = kDraws;
  // Standard errors over a million draws: mean 1e-3, variance sqrt(2)e-3, fourth moment sqrt(96)e-3;
  // P(|x| > 2) = erfc(sqrt(2)) = 0.0455, its standard error 2.1e-4. Bounds at five of them.
  EXPECT_NEAR(sum / n, 0.0, 5e-3);
  EXPECT_NEAR(sum2 / n, 1.0, 5.0 * std::sqrt(2.0) * 1e-3);
  EXPECT_NEAR(sum4 / n, 3.0, 5.0 * std::sqrt(96.0) * 1e-3);
  EXPECT_NEAR(beyond_2 / n, std::erfc(std::sqrt(2.0)), 5.0 * 2.1e-4);
}

TEST(NoiseEngine, SeedsAndModesGiveTheirOwnStreams) {
  NoiseEngine a(1, true), b(2, true), c(1, false), d(1, true);
  int same_ab = 0, same_ac = 0;
  for (int i = 0; i < 100; ++i) {
    const auto va = a();
    same_ab += va == b() ? 1 : 0;
    same_ac += va == c() ? 1 : 0;
    ASSERT_EQ(va, d()) << i;  // a seed's stream is reproducible
  }
  EXPECT_EQ(same_ab, 0);
  EXPECT_EQ(same_ac, 0);
}

}  // namespace
}  // namespace deflex::cell
