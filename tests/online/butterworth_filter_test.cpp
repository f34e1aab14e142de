// The Butterworth low-pass against the analytic response: the closed-form gain of the bilinear
// design, and the exact discrete-time response evaluated here from the analog prototype's poles
// through the bilinear map, compared with a long sinusoid filtered and fitted for amplitude and phase.
#include <cmath>
#include <complex>

#include <gtest/gtest.h>

#include "deflex/online/butterworth_filter.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

using cd = std::complex<double>;

// H(e^{jw}) of the bilinear-transformed Butterworth prototype, computed from its poles:
// H_a(s) = prod_k (-p_k) / (s - p_k), p_k = wa exp(j(pi/2 + (2k+1)pi/(2n))), s = 2 fs (z-1)/(z+1).
cd expected_response(int n, double fc, double fs, double f) {
  const double pi = std::acos(-1.0);
  const double wa = 2.0 * fs * std::tan(pi * fc / fs);
  const cd z = std::polar(1.0, 2.0 * pi * f / fs);
  const cd s = 2.0 * fs * (z - 1.0) / (z + 1.0);
  cd h = 1.0;
  for (int k = 0; k < n; ++k) {
    const cd p = std::polar(wa, pi / 2.0 + (2.0 * k + 1.0) * pi / (2.0 * n));
    h *= -p / (s - p);
  }
  return h;
}

// Closed form of the bilinear Butterworth magnitude: the analog |H| at the pre-warped frequency.
double closed_form_gain(int n, double fc, double fs, double f) {
  const double pi = std::acos(-1.0);
  const double r = std::tan(pi * f / fs) / std::tan(pi * fc / fs);
  return 1.0 / std::sqrt(1.0 + std::pow(r, 2.0 * n));
}

struct Fit {
  double gain, phase;
};

// Filters a unit sinusoid on channel 0 and fits y = a sin + b cos over the second half.
Fit measure(ButterworthLowPass filter, double fs, double f) {
  const double pi = std::acos(-1.0);
  const int samples = 40000;
  filter.reset(Vector6::Zero());
  double ss = 0, sc = 0, cc = 0, ys = 0, yc = 0;
  for (int i = 0; i < samples; ++i) {
    const double ph = 2.0 * pi * f * i / fs;
    Vector6 x = Vector6::Zero();
    x[0] = std::sin(ph);
    const double y = filter.step(x)[0];
    if (i >= samples / 2) {
      const double s = std::sin(ph), c = std::cos(ph);
      ss += s * s;
      sc += s * c;
      cc += c * c;
      ys += y * s;
      yc += y * c;
    }
  }
  const double det = ss * cc - sc * sc;
  const double a = (ys * cc - yc * sc) / det;
  const double b = (yc * ss - ys * sc) / det;
  return {std::hypot(a, b), std::atan2(b, a)};
}

TEST(ButterworthFilter, GainAndPhaseMatchTheAnalyticResponse) {
  const double fs = 1000.0;
  for (int order : {1, 2, 3, 4, 5}) {
    for (double fc : {25.0, 80.0}) {
      const ButterworthLowPass filter(design_butterworth_lowpass(order, fc, fs));
      for (double f : {2.0, 10.0, fc, 40.0, 100.0, 250.0}) {
        const cd h = expected_response(order, fc, fs, f);
        ASSERT_NEAR(std::abs(h), closed_form_gain(order, fc, fs, f), 1e-12) << "independent references disagree";
        const Fit m = measure(filter, fs, f);
        EXPECT_NEAR(m.gain, std::abs(h), 1e-6) << "order " << order << " fc " << fc << " f " << f;
        double dphase = m.phase - std::arg(h);
        dphase = std::remainder(dphase, 2.0 * std::acos(-1.0));
        EXPECT_NEAR(dphase, 0.0, 1e-5) << "order " << order << " fc " << fc << " f " << f;
      }
    }
  }
}

TEST(ButterworthFilter, CutOffIsMinus3dBAndDcGainIsOne) {
  for (int order : {1, 2, 4, 8}) {
    const ButterworthLowPass filter(design_butterworth_lowpass(order, 25.0, 250.0));
    EXPECT_NEAR(measure(filter, 250.0, 25.0).gain, 1.0 / std::sqrt(2.0), 1e-6) << order;
    ButterworthLowPass f2 = filter;
    Vector6 x = Vector6::Constant(3.5);
    Vector6 y;
    for (int i = 0; i < 5000; ++i) {
      y = f2.step(x);
    }
    EXPECT_NEAR(y[3], 3.5, 1e-9);
  }
}

TEST(ButterworthFilter, PrimesOnTheFirstSampleWithoutTransient) {
  ButterworthLowPass f(design_butterworth_lowpass(4, 25.0, 1000.0));
  Vector6 x;
  x << 1, -2, 3, -4, 5, -6;
  for (int i = 0; i < 10; ++i) {
    EXPECT_LT((f.step(x) - x).norm(), 1e-12);
  }
}

TEST(ButterworthFilter, RejectsBadDesigns) {
  EXPECT_THROW((void)design_butterworth_lowpass(0, 25, 1000), InputError);
  EXPECT_THROW((void)design_butterworth_lowpass(9, 25, 1000), InputError);
  EXPECT_THROW((void)design_butterworth_lowpass(2, 500, 1000), InputError);
  EXPECT_THROW((void)design_butterworth_lowpass(2, std::nan(""), 1000), InputError);
}

TEST(ButterworthFilter, StepDoesNotAllocate) {
  ButterworthLowPass f(design_butterworth_lowpass(4, 25.0, 1000.0));
  Vector6 x = Vector6::Ones();
  test::AllocationGuard guard;
  for (int i = 0; i < 100; ++i) {
    x = f.step(x);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
