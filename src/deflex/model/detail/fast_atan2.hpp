// atan2 for the analytic inverse kinematics, which calls it about twenty times per pose: glibc's
// atan2 saves and restores the floating-point rounding mode on every call (about half its cost,
// measured in the model benchmark), which this one does not need. Same result as std::atan2 to a
// few units in the last place (tests/model/fast_atan2_test.cpp), same signed-zero and quadrant
// conventions; non-finite input and (0, 0) go to std::atan2.
//
// Method: reduce to t = min/max in [0, 1]; split t at the nearest c = k/16 and use
// atan(t) = atan(c) + atan(u), u = (t - c) / (1 + t c), |u| <= 1/32; atan(u) by its Taylor series
// to u^11 (the first term left out is below 1e-19 relative).
//
// The IK itself takes its angles with unit_vector_angle() below, which needs no division because
// every pair it is given is a cosine and a sine; fast_atan2() is its way out for anything else.
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

// asin(k/64) and cos(asin(k/64)), k = 0..47, correctly rounded: unit_vector_angle()'s reference angles.
inline constexpr double kUnitAngleAsin[48] = {0.0,
                                              0.01562563585273695,
                                              0.031255088499495154,
                                              0.04689218313328187,
                                              0.06254076179649139,
                                              0.07820469193475428,
                                              0.09388787510751648,
                                              0.1095942559105338,
                                              0.1253278311680654,
                                              0.1410926594558939,
                                              0.1568928710204612,
                                              0.17273267816447335,
                                              0.1886163861754041,
                                              0.20454840488055165,
                                              0.22053326092083333,
                                              0.2365756108455429,
                                              0.25268025514207865,
                                              0.26885215332847107,
                                              0.2850964402527462,
                                              0.30141844376218346,
                                              0.31782370392788073,
                                              0.3343179940363684,
                                              0.3509073435910811,
                                              0.3675980636032758,
                                              0.3843967744956391,
                                              0.4013104369938405,
                                              0.4183463864434681,
                                              0.43551237106443375,
                                              0.4528165947449256,
                                              0.47026776508597007,
                                              0.48787514754029293,
                                              0.5056486266513965,
                                              0.5235987755982989,
                                              0.541736935498202,
                                              0.560075306226582,
                                              0.5786270508990997,
                                              0.5974064166453502,
                                              0.6164288749217072,
                                              0.6357112854013022,
                                              0.6552720885009422,
                                              0.6751315329370317,
                                              0.6953119464567681,
                                              0.7158380602251112,
                                              0.7367374004896439,
                                              0.758040765426236,
                                              0.7797828109803135,
                                              0.8020027778036185,
                                              0.8247454031854757};
inline constexpr double kUnitAngleCos[48] = {1.0,
                                             0.9998779222360098,
                                             0.9995115994824673,
                                             0.9989007630265381,
                                             0.998044963916957,
                                             0.9969435713093294,
                                             0.9955957701296244,
                                             0.9940005580355576,
                                             0.9921567416492215,
                                             0.9900629320275555,
                                             0.9877175393299442,
                                             0.9851187666342571,
                                             0.982264602843857,
                                             0.9791528146183311,
                                             0.9757809372497497,
                                             0.9721462643938925,
                                             0.9682458365518543,
                                             0.9640764281813968,
                                             0.9596345332990055,
                                             0.9549163494123452,
                                             0.9499177595981665,
                                             0.94463431251199,
                                             0.939061200082295,
                                             0.9331932326024445,
                                             0.9270248108869579,
                                             0.9205498951034647,
                                             0.9137619698258403,
                                             0.9066540047752505,
                                             0.899218410621135,
                                             0.8914469890997445,
                                             0.8833308765689106,
                                             0.8748604799480887,
                                             0.8660254037844386,
                                             0.8568143669284497,
                                             0.8472151069828724,
                                             0.8372142702886759,
                                             0.8267972847076845,
                                             0.8159482118216818,
                                             0.8046495743489833,
                                             0.7928821535228296,
                                             0.7806247497997998,
                                             0.7678538984566009,
                                             0.7545435292281023,
                                             0.7406645559057082,
                                             0.7261843774138906,
                                             0.7110662658114221,
                                             0.6952686081652184,
                                             0.678743957155421};

/// The angle of a unit vector (c, s), atan2(s, c), without a division: every angle the analytic IK
/// takes is of a cosine and sine pair of unit length to a few units in the last place, and the two
/// divisions of fast_atan2() were most of its time. Same result as std::atan2 to a few units in the
/// last place for such vectors (tests/model/fast_atan2_test.cpp); a vector of length 1 + e moves the
/// result by at most 0.012 e. NaN and vectors far from unit length (a component of magnitude above
/// 0.73 in the first octant's sine) go to fast_atan2(); other lengths give a wrong angle.
///
/// Method: fold (c, s) into the first octant, sine x in [0, 0.7072]; take the reference angle
/// a_k = asin(k/64) nearest in sine, k = round(64 x); the rest of the angle is asin of
/// x cos(a_k) - y k/64 (y the folded cosine), |.| <= 0.0111, by its Taylor series to the 7th power
/// (the first term left out is below 1e-19).
[[nodiscard, gnu::always_inline]] inline double unit_vector_angle(double s, double c) {
  constexpr double kHalfPi = 1.5707963267948966;
  constexpr double kPiValue = 3.141592653589793;
  const double ac = std::fabs(c);
  const double as = std::fabs(s);
  const bool swap = as > ac;
  const double x = swap ? ac : as;  // the folded sine
  const double y = swap ? as : ac;  // and cosine
  if (!(x < 0.73)) {
    return fast_atan2(s, c);  // NaN, or not a unit vector
  }
  const int k = static_cast<int>(x * 64.0 + 0.5);  // NOLINT(bugprone-incorrect-roundings): x >= 0
  const double u = x * kUnitAngleCos[k] - y * (k * (1.0 / 64.0));
  const double z = u * u;
  double r = kUnitAngleAsin[k] + (u + u * z * (1.0 / 6.0 + z * (3.0 / 40.0 + z * (5.0 / 112.0))));
  if (swap) {
    r = kHalfPi - r;
  }
  if (std::signbit(c)) {
    r = kPiValue - r;
  }
  return std::signbit(s) ? -r : r;
}

}  // namespace deflex
