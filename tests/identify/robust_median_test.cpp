// The identification's median of residual norms against a plain sort of a copy.
#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/identify/detail/robust_median.hpp"

namespace deflex {
namespace {

// The textbook median: sort a copy, the middle value or the mean of the two middle values.
double sorted_median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size();
  return m % 2 == 1 ? v[m / 2] : 0.5 * (v[m / 2] + v[m / 2 - 1]);
}

double median_of(const std::vector<double>& v) {
  return median_of_nonnegative(v.size(), [&](std::size_t i) { return v[i]; });
}

TEST(RobustMedian, EqualsTheMiddleOfASortedCopyBitForBit) {
  std::mt19937 rng(3);
  std::lognormal_distribution<double> spread(-10.0, 2.0);  // residual norms over many octaves
  for (std::size_t m : {1U, 2U, 3U, 4U, 5U, 100U, 101U, 4096U, 100001U, 250000U}) {
    std::vector<double> v(m);
    for (double& x : v) {
      x = spread(rng);
    }
    EXPECT_EQ(median_of(v), sorted_median(v)) << m << " values";
  }
}

TEST(RobustMedian, TiesZerosAndValuesSharingTheirTopBitsGiveTheSortedMedian) {
  // Many repeats of a few values (a file of 60 measurements repeated), zeros (exact fits), and values so close
  // that they all fall in one histogram bucket (every value is then selected among).
  std::vector<double> repeats, zeros, close;
  for (int i = 0; i < 60000; ++i) {
    repeats.push_back(1e-5 * (1 + i % 60));
    zeros.push_back(i % 3 == 0 ? 0.0 : 1e-6 * i);
    close.push_back(1.0 + 1e-12 * ((i * 7919) % 60000));
  }
  EXPECT_EQ(median_of(repeats), sorted_median(repeats));
  EXPECT_EQ(median_of(zeros), sorted_median(zeros));
  EXPECT_EQ(median_of(close), sorted_median(close));
  close.pop_back();  // and an odd count
  EXPECT_EQ(median_of(close), sorted_median(close));
  EXPECT_EQ(median_of({0.0, 0.0}), 0.0);
  EXPECT_EQ(median_of({}), 0.0);
  EXPECT_EQ(median_of({2.0, 1.0}), 1.5);  // closed form: the mean of the two
}

}  // namespace
}  // namespace deflex
