// The link delay measurement against a delay line built here: the feedback is the reference of a
// known time ago, so the estimate must find that time; at rest nothing is measured; a stray
// mismatch once settled is left out.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/online/delay_estimator.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

JointVector path_at(double t) {
  JointVector q(6);
  for (int j = 0; j < 6; ++j) q[j] = 0.1 * (j + 1) * std::sin(0.7 * t + j) + 0.02 * t;
  return q;
}

TEST(DelayEstimator, FindsTheDelayOfADelayLine) {
  for (double delay : {0.012, 0.048, 0.1}) {
    DelayEstimator e(0.05);
    for (int k = 0; k < 2000; ++k) {
      const double t = 0.004 * k;
      e.record_reference(t, path_at(t));
      e.observe_feedback(t, path_at(t - delay));
    }
    ASSERT_TRUE(e.measured()) << delay;
    EXPECT_NEAR(e.delay_s(), delay, 2e-4) << delay;
    EXPECT_NEAR(e.mean_s(), delay, 5e-4) << delay;
  }
}

TEST(DelayEstimator, MeasuresNothingAtRestAndIgnoresMismatchesOnceSettled) {
  DelayEstimator e(0.05);
  const JointVector rest = path_at(0.0);
  for (int k = 0; k < 200; ++k) {
    e.record_reference(0.004 * k, rest);
    e.observe_feedback(0.004 * k, rest);
  }
  EXPECT_FALSE(e.measured());
  EXPECT_DOUBLE_EQ(e.delay_s(), 0.05);  // still the assumed value
  for (int k = 200; k < 600; ++k) {
    const double t = 0.004 * k;
    e.record_reference(t, path_at(t));
    e.observe_feedback(t, path_at(t - 0.06));
  }
  // The jump from rest onto the moving path gave a few wrong matches first; the estimate recovers.
  const double settled = e.delay_s();
  EXPECT_NEAR(settled, 0.06, 1e-3);
  // One feedback that matches a reference 0.3 s old: a mismatch, not a new delay (the jump there is
  // no motion of a delay line, so it is not even measured).
  const std::uint64_t measurements = e.measurements();
  e.observe_feedback(0.004 * 600, path_at(0.004 * 600 - 0.36));
  EXPECT_EQ(e.measurements(), measurements);
  EXPECT_DOUBLE_EQ(e.delay_s(), settled);
  // A mismatch the arm moves into smoothly is measured, and left out as an outlier once settled.
  const std::uint64_t outliers = e.outliers();
  for (int k = 601; k < 610; ++k) {
    const double t = 0.004 * k;
    e.record_reference(t, path_at(t));
    e.observe_feedback(t, path_at(t - 0.36));
  }
  EXPECT_GT(e.outliers(), outliers);
  EXPECT_DOUBLE_EQ(e.delay_s(), settled);
  test::AllocationGuard guard;
  e.record_reference(3.0, path_at(3.0));
  e.observe_feedback(3.0, path_at(2.94));
  EXPECT_EQ(guard.allocations(), 0u);
}

TEST(DelayEstimator, AnArmThatHasNotStartedYetGivesNoMeasurement) {
  // The reference starts moving at t = 1 s; the arm, 80 ms behind, stands at the start until then.
  // Matched against the reference's start, the standing arm would "measure" the time since the
  // reference left it (80 ms, then more); only the moving arm measures the delay.
  const double delay = 0.08;
  const auto ref = [](double t) { return path_at(std::max(0.0, t - 1.0)); };
  DelayEstimator e(0.05);
  double first = NAN;
  for (int k = 0; k < 750; ++k) {
    const double t = 0.004 * k;
    e.record_reference(t, ref(t));
    e.observe_feedback(t, ref(t - delay));
    if (e.measured() && std::isnan(first)) first = e.last_measurement_s();
  }
  ASSERT_TRUE(e.measured());
  EXPECT_NEAR(first, delay, 2e-3);       // the first measurement is already the delay
  EXPECT_NEAR(e.mean_s(), delay, 1e-3);  // and no early wrong one weighs on the mean
  EXPECT_EQ(e.outliers(), 0u);
}

TEST(DelayEstimator, ScatteredMismatchesNeverRestartItAChangedLinkDoes) {
  DelayEstimator e(0.05);
  double t = 0.0;
  const auto step = [&](double delay) {
    t += 0.004;
    e.record_reference(t, path_at(t));
    e.observe_feedback(t, path_at(t - delay));
  };
  for (int k = 0; k < 500; ++k) step(0.06);
  ASSERT_NEAR(e.delay_s(), 0.06, 1e-3);
  // Forty mismatches in a row that disagree with each other (an arm coming to rest, a reversal),
  // each moving as the reference does: measured, left out, the estimate stays.
  for (int k = 0; k < 40; ++k) {
    const double d = (k / 5) % 2 == 0 ? 0.2 : 0.4;
    step(d);
  }
  EXPECT_NEAR(e.delay_s(), 0.06, 1e-3);
  EXPECT_NEAR(e.mean_s(), 0.06, 1e-3);
  EXPECT_GE(e.outliers(), 20u);
  // The link's delay really changes to 0.2 s: after a run of agreeing measurements the estimate
  // starts again from them.
  for (int k = 0; k < 30; ++k) step(0.2);
  EXPECT_NEAR(e.delay_s(), 0.2, 2e-3);
  EXPECT_NEAR(e.mean_s(), 0.2, 2e-3);
}

}  // namespace
}  // namespace deflex
