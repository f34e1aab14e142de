// An independent milling force for the tests: the per-tooth formulas written out in the textbook's
// frame (feed along +x, tool axis +z from the tip into the spindle, teeth turning clockwise seen from
// above for M3), summed over teeth and thin axial slices with plain loops, no closed form. The
// library's results are held against these sums.
//
// A tooth at immersion angle phi (measured from +y, in the turning direction) sits at
// (sin phi, cos phi) for M3 and (sin phi, -cos phi) for M4, and moves along d/dphi of that. The cut
// pushes the tool against the tooth's motion (tangential force), towards the tool's centre (radial)
// and, for positive axial coefficients, from the spindle towards the tip (axial): a right-hand helix
// pulls the tool out of its holder. A corner slice at edge angle kappa tilts the radial force to the
// edge's normal  sin(kappa) r - cos(kappa) z  and the axial one to the edge's direction
// cos(kappa) r + sin(kappa) z, with chip area fz sin(phi) dz and edge length dS = r dkappa.
#pragma once

#include <cmath>

#include "deflex/model/types.hpp"

namespace deflex::test {

struct TextbookCut {
  double diameter_m = 10e-3;
  double corner_radius_m = 0.0;
  int flutes = 3;
  double helix_rad = 0.0;
  double fz_m = 1e-4;
  bool m3 = true;
  double entry_rad = 0.0, exit_rad = kPi;
  double z_lo_m = 0.0, z_hi_m = 5e-3;
  // Al7075-T6 (reference/machining.md), SI.
  double ktc = 767e6, krc = 168.8e6, kac = 222e6, kte = 27.7e3, kre = 26.6e3, kae = 0.7e3;
};

/// Force [0..2] and moment about the tip [3..5] on the tool at spindle rotation theta (tooth 0's tip at
/// phi = theta), xyz as above, from `slices` axial slices (the corner in kappa steps, the side in z).
inline Vector6 textbook_wrench(const TextbookCut& c, double theta, int slices) {
  const double R = 0.5 * c.diameter_m, rc = c.corner_radius_m, side = c.m3 ? 1.0 : -1.0;
  Vector6 w = Vector6::Zero();
  auto add_element = [&](double z, double radius, double kappa, double dz, double ds) {
    for (int j = 0; j < c.flutes; ++j) {
      double phi = theta + 2.0 * kPi * j / c.flutes - z * std::tan(c.helix_rad) / R;
      phi = std::fmod(phi, 2.0 * kPi);
      if (phi < 0.0) phi += 2.0 * kPi;
      if (phi < c.entry_rad || phi > c.exit_rad) continue;
      const Vector3 r(std::sin(phi), side * std::cos(phi), 0.0);
      const Vector3 t(std::cos(phi), -side * std::sin(phi), 0.0);
      const Vector3 z_axis = Vector3::UnitZ();
      const double h = c.fz_m * std::sin(phi);
      const double ft = c.ktc * h * dz + c.kte * ds, fr = c.krc * h * dz + c.kre * ds, fa = c.kac * h * dz + c.kae * ds;
      const Vector3 normal = std::sin(kappa) * r - std::cos(kappa) * z_axis;
      const Vector3 along = std::cos(kappa) * r + std::sin(kappa) * z_axis;
      const Vector3 f = -ft * t - fr * normal - fa * along;
      const Vector3 p = radius * r + z * z_axis;
      w.head<3>() += f;
      w.tail<3>() += p.cross(f);
    }
  };
  // The corner, in kappa steps (z = rc (1 - cos kappa)).
  if (rc > 0.0 && c.z_lo_m < rc) {
    const double k1 = std::acos(1.0 - c.z_lo_m / rc), k2 = std::acos(1.0 - std::min(c.z_hi_m, rc) / rc);
    const double dk = (k2 - k1) / slices;
    for (int i = 0; i < slices; ++i) {
      const double k = k1 + (i + 0.5) * dk;
      add_element(rc * (1.0 - std::cos(k)), R - rc + rc * std::sin(k), k, rc * std::sin(k) * dk, rc * dk);
    }
  }
  const double lo = std::max(c.z_lo_m, rc);
  if (c.z_hi_m > lo) {
    const double dz = (c.z_hi_m - lo) / slices;
    for (int i = 0; i < slices; ++i) add_element(lo + (i + 0.5) * dz, R, 0.5 * kPi, dz, dz);
  }
  return w;
}

/// The mean over a revolution sampled at `steps` rotation angles.
inline Vector6 textbook_average(const TextbookCut& c, int steps, int slices) {
  Vector6 sum = Vector6::Zero();
  for (int i = 0; i < steps; ++i) sum += textbook_wrench(c, 2.0 * kPi * (i + 0.5) / steps, slices);
  return sum / steps;
}

}  // namespace deflex::test
