// The correction smoother against closed forms and against the controller's own check: a stream
// through it never exceeds the velocity, acceleration and jerk it was built for (measured by
// FANUC's finite differences, fanuc_j519::MotionCheck, on wild inputs: steps of a radian, noise, a
// NaN-free random walk), its step response is the two boxes' convolution counted here pair by pair,
// it never overshoots, it refuses limits it cannot meet, and step() does not allocate.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "deflex/link/correction_smoother.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/wire/fanuc_j519.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

constexpr double kDeg = kPi / 180.0;

// CRX-10iA/L's strictest table values read on a pendant (../shared/reference/fanuc_j519.md), with
// the correction given a tenth of each (the program takes the rest).
SmootherLimits crx_share() {
  SmootherLimits l;
  l.cycle_s = 0.008;
  l.step_rad = 0.002 * kDeg;
  l.acceleration = 26.5 * kDeg;
  l.jerk = 124.0 * kDeg;
  return l;
}

TEST(CorrectionSmoother, TapsAreTheSmallestThatMeetTheClosedForms) {
  const SmootherLimits l = crx_share();
  const std::size_t n = CorrectionSmoother::taps_for(l);
  // jerk: 4 s / (N^2 T^3) <= J  ->  N >= sqrt(4 * 0.002 / (124 * 0.008^3)) = 11.23; acceleration: N >= 2 s / (A T^2)
  // = 2.36
  EXPECT_EQ(n, 12u);
  const CorrectionSmoother smoother(l, 6);
  EXPECT_LE(smoother.jerk_bound(), l.jerk);
  EXPECT_LE(smoother.acceleration_bound(), l.acceleration);
  EXPECT_NEAR(smoother.delay_s(), 11 * 0.008, 1e-12);
  SmootherLimits one_less = l;
  one_less.jerk = 4.0 * l.step_rad / (11.0 * 11.0 * std::pow(l.cycle_s, 3));  // exactly met by N = 11
  EXPECT_EQ(CorrectionSmoother::taps_for(one_less), 11u);
}

TEST(CorrectionSmoother, TheControllersCheckNeverTripsOnWhatItSends) {
  const SmootherLimits l = crx_share();
  CorrectionSmoother smoother(l, 6);
  std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> limits{};
  limits.fill(
      {smoother.velocity_bound() / kDeg * (1 + 1e-9), l.acceleration / kDeg * (1 + 1e-9), l.jerk / kDeg * (1 + 1e-9)});
  fanuc_j519::MotionCheck check(l.cycle_s, 6, limits);
  check.reset({});
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05 * kDeg);
  std::bernoulli_distribution jump(0.01);
  std::uniform_real_distribution<double> level(-1.0, 1.0);
  JointVector wanted = JointVector::Zero(6);
  for (int cycle = 0; cycle < 20000; ++cycle) {
    for (int j = 0; j < 6; ++j) {
      if (jump(rng)) wanted[j] = level(rng);  // a radian's step at any time
      wanted[j] += noise(rng);
    }
    const JointVector& out = smoother.step(wanted);
    std::array<double, fanuc_j519::kAxes> deg{};
    for (int j = 0; j < 6; ++j) deg[static_cast<std::size_t>(j)] = out[j] / kDeg;
    std::size_t axis = 0;
    double value = 0.0;
    ASSERT_EQ(check.push(deg, axis, value), fanuc_j519::LimitExceeded::kNone)
        << "cycle " << cycle << " axis " << axis << " value " << value;
  }
  // And the bounds are reached, not loose by orders of magnitude: a reversal of the rate-limited
  // correction (+s to -s a cycle) gives half the jerk bound, 2 s / N^2.
  EXPECT_GT(check.peak().jerk, 0.45 * smoother.jerk_bound() / kDeg);
  EXPECT_GT(check.peak().velocity, 0.99 * smoother.velocity_bound() / kDeg);
}

TEST(CorrectionSmoother, StepResponseIsTheTwoBoxesConvolution) {
  SmootherLimits l = crx_share();
  l.step_rad = 1.0;  // no rate limit on a 1 mrad step
  l.acceleration = 1e9;
  l.jerk = 4.0 / (5.0 * 5.0 * std::pow(l.cycle_s, 3));  // N = 5
  CorrectionSmoother smoother(l, 1);
  ASSERT_EQ(smoother.taps(), 5u);
  const double h = 1e-3;
  JointVector wanted(1);
  wanted[0] = h;
  for (int k = 0; k < 12; ++k) {
    const double y = smoother.step(wanted)[0];
    // After k + 1 samples of the step: the share of the N^2 pairs (i, j) of the two boxes' taps with
    // i + j <= k.
    int pairs = 0;
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) pairs += (i + j <= k) ? 1 : 0;
    }
    EXPECT_NEAR(y, h * pairs / 25.0, 1e-15) << "cycle " << k;
  }
}

TEST(CorrectionSmoother, NeverLeavesTheRangeOfWhatItWasAsked) {
  CorrectionSmoother smoother(crx_share(), 2);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> level(-0.01, 0.02);
  JointVector wanted(2);
  double lo = 0.0;
  double hi = 0.0;
  for (int cycle = 0; cycle < 5000; ++cycle) {
    if (cycle % 37 == 0) {
      wanted[0] = level(rng);
      wanted[1] = -wanted[0];
    }
    lo = std::min({lo, wanted[0], wanted[1]});
    hi = std::max({hi, wanted[0], wanted[1]});
    const JointVector& out = smoother.step(wanted);
    ASSERT_GE(out.minCoeff(), lo - 1e-15);
    ASSERT_LE(out.maxCoeff(), hi + 1e-15);
  }
}

TEST(CorrectionSmoother, RefusesLimitsItCannotMeetAndSaysWhy) {
  SmootherLimits l = crx_share();
  l.jerk = 0.0;
  EXPECT_THROW((void)CorrectionSmoother::taps_for(l), InputError);
  l = crx_share();
  l.cycle_s = std::nan("");
  EXPECT_THROW((void)CorrectionSmoother::taps_for(l), InputError);
  l = crx_share();
  l.step_rad = 1.0 * kDeg;  // needs ~270 cycles of averaging at this jerk
  try {
    (void)CorrectionSmoother::taps_for(l);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lower the correction's rate bound"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CorrectionSmoother(crx_share(), 0), InputError);
}

TEST(CorrectionSmoother, StepDoesNotAllocate) {
  CorrectionSmoother smoother(crx_share(), 6);
  JointVector wanted = JointVector::Constant(6, 0.01);
  test::AllocationGuard guard;
  for (int i = 0; i < 1000; ++i) {
    wanted[i % 6] = -wanted[i % 6];
    (void)smoother.step(wanted);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
