// Synthetic tracker traces for the evaluation tests: circles, lines and noise with known geometry.
#pragma once

#include <cmath>
#include <random>

#include "deflex/model/tracker_trace.hpp"

namespace deflex::test {

/// Circle of radius r (m) about `centre` in the plane z = centre.z, n samples over `laps` laps,
/// anticlockwise (clockwise when `clockwise`), 1 ms apart.
inline TrackerTrace circle(double r, const Vector3& centre, int n, double laps = 1.0, bool clockwise = false,
                           double phase = 0.0) {
  TrackerTrace t;
  for (int i = 0; i < n; ++i) {
    const double a = phase + (clockwise ? -1.0 : 1.0) * 2.0 * kPi * laps * i / n;
    t.push_back({i * 1e-3, centre + Vector3(r * std::cos(a), r * std::sin(a), 0.0)});
  }
  return t;
}

/// Closed circle: the first sample repeated at the end.
inline TrackerTrace closed_circle(double r, const Vector3& centre, int n, bool clockwise = false) {
  TrackerTrace t = circle(r, centre, n, 1.0, clockwise);
  t.push_back({n * 1e-3, t.front().p_m});
  return t;
}

inline TrackerTrace shifted(TrackerTrace t, const Vector3& d) {
  for (auto& s : t) {
    s.p_m += d;
  }
  return t;
}

inline TrackerTrace with_noise(TrackerTrace t, double sigma_m, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, sigma_m);
  for (auto& s : t) {
    s.p_m += Vector3(n(rng), n(rng), n(rng));
  }
  return t;
}

}  // namespace deflex::test
