// atan2 for the analytic inverse kinematics, which calls it about twenty times per pose: glibc's
// atan2 saves and restores the floating-point rounding mode on every call (about half its cost,
// measured in the model benchmark), which this one does not need. Same result as std::atan2 to a
// few units in the last place (tests/model/fast_atan2_test.cpp), same signed-zero and quadrant
// conventions; non-finite input and (0, 0) go to std::atan2.
//
// Method: reduce to t = min/max in [0, 1]; split t at the nearest c = k/16 and use
// atan(t) = atan(c) + atan(u), u = (t - c) / (1 + t c), |u| <= 1/32; atan(u) by its Taylor series
// to u^11 (the first term left out is below 1e-19 relative).
#pragma once

#include <cmath>

namespace deflex {

[[nodiscard]] inline double fast_atan2(double y, double x) {
  // atan(k/16), k = 0..16, correctly rounded.
  static constexpr double kAtanTable[17] = {0.0,
                                            0.06241880999595735,
                                            0.12435499454676144,
                                            0.18534794999569476,
                                            0.24497866312686414,
                                            0.3028848683749714,
                                            0.35877067027057225,
                                            0.4124104415973873,
                                            0.4636476090008061,
                                            0.5123894603107377,
                                            0.5585993153435624,
                                            0.6022873461349642,
                                            0.6435011087932844,
                                            0.6823165548747481,
                                            0.7188299996216245,
                                            0.7531512809621944,
                                            0.7853981633974483};
  constexpr double kHalfPi = 1.5707963267948966;
  constexpr double kPiValue = 3.141592653589793;
  const double ax = std::fabs(x);
  const double ay = std::fabs(y);
  const bool swap = ay > ax;
  const double num = swap ? ax : ay;
  const double den = swap ? ay : ax;
  if (!(den > 0.0) || !(den < HUGE_VAL) || !(num < HUGE_VAL)) {
    return std::atan2(y, x);  // zeros, infinities, NaN
  }
  // num / den is in [0, 1]: adding 0.5 and truncating rounds to nearest, without lround's library
  // call in the kinematics kernel.
  const int k = static_cast<int>(num * 16.0 / den + 0.5);  // NOLINT(bugprone-incorrect-roundings)
  const double c = k * (1.0 / 16.0);
  const double u = (num - c * den) / (den + c * num);
  const double z = u * u;
  const double p = u + u * z * (-1.0 / 3.0 + z * (1.0 / 5.0 + z * (-1.0 / 7.0 + z * (1.0 / 9.0 + z * (-1.0 / 11.0)))));
  double r = kAtanTable[k] + p;
  if (swap) {
    r = kHalfPi - r;
  }
  if (std::signbit(x)) {
    r = kPiValue - r;
  }
  return std::signbit(y) ? -r : r;
}

}  // namespace deflex
