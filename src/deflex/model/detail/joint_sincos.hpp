// Sine and cosine of a robot's joint angles in one pass. Written here rather than calling the C
// library because forward kinematics needs both of up to seven angles every call and the library's
// sincos() is a call per angle with a general range reduction: in the FK benchmark it was 44 % of the
// time (6 calls, about 65 ns of 147 ns). This pass has no call and no branch per angle, so the
// compiler interleaves the angles; it is within 1 ulp of std::sin/std::cos on 14 million angles
// (tests/model/kinematics_kernel_test.cpp holds it to 2 ulp on random angles, next to the quadrant
// edges and on them). Angles beyond +-1e5 rad (never a joint's) go to the C library.
//
// Method: the angle is reduced to r in [-pi/4, pi/4] with k = round(2 x / pi) by a four-part
// Cody-Waite subtraction of k pi/2 (the first part has 33 significant bits, so k times it is exact
// for |k| < 2^20), then sin r and cos r come from the minimax polynomials of degree 13 and 14 whose
// coefficients fdlibm publishes (k_sin.c, k_cos.c: error below 2^-58 on [-pi/4, pi/4]), and the
// quadrant k mod 4 swaps and signs them.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "deflex/model/types.hpp"

namespace deflex::detail {

/// c[i] = cos(angle[i]), s[i] = sin(angle[i]) for i < n (n <= kMaxJoints).
inline void joint_sincos(const std::array<double, kMaxJoints>& angle, int n, std::array<double, kMaxJoints>& c,
                         std::array<double, kMaxJoints>& s) {
  constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  constexpr double kPio2Part1 = 1.57079632673412561417e+00;  // first 33 bits of pi/2
  constexpr double kPio2Part2 = 6.07710050630396597660e-11;  // next 33 bits
  constexpr double kPio2Part3 = 2.02226624871116645580e-21;  // the next 33 bits
  constexpr double kPio2Part4 = 8.47842766036889956997e-32;  // the rest, to 2^-150
  constexpr double kS1 = -1.66666666666666324348e-01, kS2 = 8.33333333332248946124e-03,
                   kS3 = -1.98412698298579493134e-04, kS4 = 2.75573137070700676789e-06,
                   kS5 = -2.50507602534068634195e-08, kS6 = 1.58969099521155010221e-10;
  constexpr double kC1 = 4.16666666666666019037e-02, kC2 = -1.38888888888741095749e-03,
                   kC3 = 2.48015872894767294178e-05, kC4 = -2.75573143513906633035e-07,
                   kC5 = 2.08757232129817482790e-09, kC6 = -1.13596475577881948265e-11;
  bool in_range = true;
  for (int i = 0; i < n; ++i) {
    in_range = in_range && std::abs(angle[static_cast<std::size_t>(i)]) <= 1e5;
  }
  if (!in_range) [[unlikely]] {
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      c[k] = std::cos(angle[k]);
      s[k] = std::sin(angle[k]);
    }
    return;
  }
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double x = angle[k];
    // Round to the nearest integer by the 1.5 * 2^52 shift (exact for |x 2/pi| < 2^51; nearbyint is a
    // library call on the baseline x86-64 the packages target).
    constexpr double kShift = 6755399441055744.0;
    const double kq = (x * kTwoOverPi + kShift) - kShift;
    const double r = (((x - kq * kPio2Part1) - kq * kPio2Part2) - kq * kPio2Part3) - kq * kPio2Part4;
    const double z = r * r;
    const double sin_r = r + r * z * (kS1 + z * (kS2 + z * (kS3 + z * (kS4 + z * (kS5 + z * kS6)))));
    const double hz = 0.5 * z;
    const double w = 1.0 - hz;
    // cos r = 1 - z/2 + z^2 (C1 + ...), with the rounding of 1 - z/2 put back (fdlibm's k_cos.c).
    const double cos_r =
        w + (((1.0 - w) - hz) + z * z * (kC1 + z * (kC2 + z * (kC3 + z * (kC4 + z * (kC5 + z * kC6))))));
    const auto quadrant = static_cast<std::int32_t>(static_cast<std::int64_t>(kq) & 3);
    const bool swap = (quadrant & 1) != 0;
    const double sin_sign = (quadrant & 2) != 0 ? -1.0 : 1.0;
    const double cos_sign = (quadrant == 1 || quadrant == 2) ? -1.0 : 1.0;
    s[k] = sin_sign * (swap ? cos_r : sin_r);
    c[k] = cos_sign * (swap ? sin_r : cos_r);
  }
}

}  // namespace deflex::detail
