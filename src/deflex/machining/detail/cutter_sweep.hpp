// The geometry of a vertical cutter sweeping a straight move, shared by the stocks: its lower surface
// at a distance from its axis, and the row of a grid inside the band a level move sweeps.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "deflex/model/types.hpp"

namespace deflex::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// The cutter's lower surface above its tip at distance d from its axis: 0 on the flat part, the
/// corner's arc beyond R - rc, +inf outside the cutter.
inline double profile(double d, double radius, double rc) noexcept {
  if (d > radius) return kInf;
  const double flat = radius - rc;
  if (d <= flat) return 0.0;
  const double u = d - flat;
  return rc - std::sqrt(std::max(0.0, rc * rc - u * u));
}

/// The x-interval of the line at height y (in the plane) within `radius` of the segment a..b (a
/// stadium, convex, so one interval): the two end discs and the band along the segment. False when
/// the line misses it.
inline bool stadium_row(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double radius, double y, double& xl,
                        double& xr) noexcept {
  if (radius < 0.0) return false;
  xl = std::numeric_limits<double>::infinity();
  xr = -xl;
  for (const Eigen::Vector2d& c : {a, b}) {
    const double dy = y - c.y(), w2 = radius * radius - dy * dy;
    if (w2 >= 0.0) {
      const double w = std::sqrt(w2);
      xl = std::min(xl, c.x() - w);
      xr = std::max(xr, c.x() + w);
    }
  }
  // The band: 0 <= t(x) <= 1 and |distance to the segment's line| <= radius, both linear in x.
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  if (len > 0.0) {
    double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
    auto clip = [&](double slope, double offset, double min, double max) {  // min <= slope x + offset <= max
      if (std::abs(slope) < 1e-300) {
        if (offset < min || offset > max) hi = lo - 1.0;
        return;
      }
      const double x1 = (min - offset) / slope, x2 = (max - offset) / slope;
      lo = std::max(lo, std::min(x1, x2));
      hi = std::min(hi, std::max(x1, x2));
    };
    const double ry = y - a.y();
    clip(d.x() / (len * len), (-a.x() * d.x() + ry * d.y()) / (len * len), 0.0, 1.0);
    clip(d.y() / len, (-a.x() * d.y() - ry * d.x()) / len, -radius, radius);
    if (hi >= lo) {
      xl = std::min(xl, lo);
      xr = std::max(xr, hi);
    }
  }
  return xr >= xl;
}

/// Within `max_tilt_rad` of +z.
inline bool vertical(const Vector3& axis, double max_tilt_rad) noexcept {
  const double n = axis.norm();
  return axis.allFinite() && n > 0.0 && axis.z() / n >= std::cos(max_tilt_rad);
}

}  // namespace deflex::detail
