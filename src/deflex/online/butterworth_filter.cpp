// Butterworth design by bilinear transform with pre-warping (see butterworth_filter.hpp).
#include "deflex/online/butterworth_filter.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

ButterworthDesign design_butterworth_lowpass(int order, double cutoff_hz, double sample_rate_hz) {
  if (order < 1 || order > kMaxButterworthOrder) {
    throw InputError(fmt::format("Butterworth order {} out of 1..{}", order, kMaxButterworthOrder));
  }
  if (!std::isfinite(cutoff_hz) || !std::isfinite(sample_rate_hz) || !(sample_rate_hz > 0.0) || !(cutoff_hz > 0.0) ||
      cutoff_hz >= 0.5 * sample_rate_hz) {
    throw InputError(fmt::format("Butterworth cut-off {} Hz must be in (0, {}) for a sample rate of {} Hz", cutoff_hz,
                                 0.5 * sample_rate_hz, sample_rate_hz));
  }
  ButterworthDesign d;
  d.order = order;
  d.cutoff_hz = cutoff_hz;
  d.sample_rate_hz = sample_rate_hz;
  d.sections = (order + 1) / 2;
  // Pre-warp so that the digital filter's -3 dB point falls exactly at cutoff_hz.
  const double k = 2.0 * sample_rate_hz;
  const double wa = k * std::tan(kPi * cutoff_hz / sample_rate_hz);
  const double wa2 = wa * wa;
  const int pairs = order / 2;
  for (int i = 0; i < pairs; ++i) {
    // Analog pole pair s = wa exp(j(pi/2 + (2i+1) pi/(2n))): section wa^2 / (s^2 + 2 zeta wa s + wa^2).
    const double zeta = std::sin((2.0 * i + 1.0) * kPi / (2.0 * order));
    const double a0 = k * k + 2.0 * zeta * wa * k + wa2;
    BiquadCoefficients& c = d.section[static_cast<std::size_t>(i)];
    c.b0 = wa2 / a0;
    c.b1 = 2.0 * wa2 / a0;
    c.b2 = wa2 / a0;
    c.a1 = (2.0 * wa2 - 2.0 * k * k) / a0;
    c.a2 = (k * k - 2.0 * zeta * wa * k + wa2) / a0;
  }
  if (order % 2 == 1) {
    // Real pole s = -wa: section wa / (s + wa).
    BiquadCoefficients& c = d.section[static_cast<std::size_t>(pairs)];
    c.b0 = wa / (k + wa);
    c.b1 = c.b0;
    c.b2 = 0.0;
    c.a1 = (wa - k) / (k + wa);
    c.a2 = 0.0;
  }
  return d;
}

double dc_group_delay_s(const ButterworthDesign& design) {
  // For H(z) = B(z)/A(z) with B = sum b_k z^-k, the group delay at w = 0 is
  // sum k b_k / sum b_k - sum k a_k / sum a_k samples (a_0 = 1); sections add.
  double samples = 0.0;
  for (int i = 0; i < design.sections; ++i) {
    const BiquadCoefficients& c = design.section[static_cast<std::size_t>(i)];
    samples += (c.b1 + 2.0 * c.b2) / (c.b0 + c.b1 + c.b2) - (c.a1 + 2.0 * c.a2) / (1.0 + c.a1 + c.a2);
  }
  return samples / design.sample_rate_hz;
}

Vector6 ButterworthLowPass::step(const Vector6& x) noexcept {
  if (!primed_) {
    reset(x);
  }
  Vector6 v = x;
  for (int i = 0; i < design_.sections; ++i) {
    const auto si = static_cast<std::size_t>(i);
    const BiquadCoefficients& c = design_.section[si];
    const Vector6 y = c.b0 * v + s1_.col(i);
    s1_.col(i) = c.b1 * v - c.a1 * y + s2_.col(i);
    s2_.col(i) = c.b2 * v - c.a2 * y;
    v = y;
  }
  return v;
}

void ButterworthLowPass::reset(const Vector6& x) noexcept {
  // Steady state of each section for a constant input u (unit DC gain, so its output is u too):
  // y = u, s2 = b2 u - a2 u, s1 = y - b0 u.
  for (int i = 0; i < design_.sections; ++i) {
    const auto si = static_cast<std::size_t>(i);
    const BiquadCoefficients& c = design_.section[si];
    s2_.col(i) = (c.b2 - c.a2) * x;
    s1_.col(i) = (1.0 - c.b0) * x;
  }
  primed_ = true;
}

}  // namespace deflex
