// Digital Butterworth low-pass filter: designed from the analog prototype by the bilinear transform
// with the cut-off pre-warped for the sample rate, run as a cascade of second-order sections (plus
// one first-order section for odd orders). Fixed-size state: stepping never allocates.
#pragma once

#include <array>

#include "deflex/model/types.hpp"

namespace deflex {

inline constexpr int kMaxButterworthOrder = 8;

/// One section y = (b0 x + b1 x1 + b2 x2 - a1 y1 - a2 y2) (a0 normalised to 1). First-order sections
/// have b2 = a2 = 0.
struct BiquadCoefficients {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
};

/// The designed filter: ceil(order/2) sections whose product is the whole transfer function.
struct ButterworthDesign {
  int order = 2;
  double cutoff_hz = 25.0;
  double sample_rate_hz = 1000.0;
  int sections = 1;
  std::array<BiquadCoefficients, (kMaxButterworthOrder + 1) / 2> section{};
};

/// Designs the filter. Throws InputError unless 1 <= order <= 8 and 0 < cutoff < sample_rate/2.
[[nodiscard]] ButterworthDesign design_butterworth_lowpass(int order, double cutoff_hz, double sample_rate_hz);

/// Group delay of the designed filter at zero frequency, s: how far a slowly changing signal lags
/// behind its filtered value (the latency-compensated strategy adds it to its lead).
[[nodiscard]] double dc_group_delay_s(const ButterworthDesign& design);

/// The Butterworth low-pass run on 6 channels at once (a wrench), Direct Form II transposed.
/// Thread safety: one thread at a time (step() changes its state).
class ButterworthLowPass {
 public:
  ButterworthLowPass() = default;
  explicit ButterworthLowPass(const ButterworthDesign& design) : design_(design) {}

  /// Filters one sample of every channel. Never allocates.
  Vector6 step(const Vector6& x) noexcept;
  /// Sets the state as if `x` had been applied for ever (no start-up transient from zero).
  void reset(const Vector6& x = Vector6::Zero()) noexcept;
  [[nodiscard]] const ButterworthDesign& design() const { return design_; }

 private:
  ButterworthDesign design_;
  // Two state values per section and channel (DF-II transposed).
  using SectionStates = Eigen::Matrix<double, 6, (kMaxButterworthOrder + 1) / 2>;  // one column a section
  SectionStates s1_ = SectionStates::Zero();
  SectionStates s2_ = SectionStates::Zero();
  bool primed_ = false;
};

}  // namespace deflex
