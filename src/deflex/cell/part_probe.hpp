// The machined part measured as a CMM, or the tracker with a probe, measures it: points probed on a
// wall or a floor of the stock the cell's tool left, each with the probe's noise, and the figures a
// machinist reads: a wall's profile against its nominal plane (ISO 1101's profile of a surface: the
// zone centred on the nominal that holds every point, with its peak-to-valley and RMS), a floor's
// flatness, a slot's or a pocket's width between two walls.
//
// The stock is the dexel model (machining/dexel_stock.hpp): a wall's position along a line is exact
// to the floating-point precision of the line's ends whatever the grid, so what the probe reads is
// the cut, not the grid. Walls are planes normal to the stock's x or y (a 3-axis part's side walls);
// floors are read from the height map underneath (exact where the tool's end face passed).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include <boost/random/normal_distribution.hpp>

#include "deflex/machining/dexel_stock.hpp"

namespace deflex::cell {

/// A nominal side wall: the plane {normal coordinate = nominal_m} of the stock frame, probed on a
/// grid of points_along x points_up points over along_lo..along_hi (the other horizontal axis) and
/// z_lo..z_hi. SI units.
struct WallSpec {
  enum class Normal { kX, kY };
  Normal normal = Normal::kY;
  double nominal_m = 0.0;
  /// The material lies at smaller coordinates along the normal than the wall (the part's side
  /// whose outward normal is +normal), or at larger ones.
  bool material_below = true;
  double along_lo_m = 0.0, along_hi_m = 0.0;
  double z_lo_m = 0.0, z_hi_m = 0.0;
  int points_along = 20;
  int points_up = 3;
  /// A point whose wall is farther than this from the nominal is not found (a probe's search).
  double search_m = 2e-3;
};

/// A wall's measured profile. Deviations d are signed along the part's outward normal: > 0 material
/// left beyond the nominal (undercut), < 0 material taken (a gouge).
struct WallProfile {
  int points = 0;   ///< points found
  int missing = 0;  ///< points with no wall within the search distance
  double mean_m = 0.0;
  double min_m = 0.0, max_m = 0.0;
  double peak_to_valley_m = 0.0;  ///< max d - min d
  double rms_m = 0.0;             ///< about the nominal
  double profile_m = 0.0;         ///< ISO 1101: width of the zone centred on the nominal, 2 max |d|
  /// The mean measured coordinate along the normal (for widths between walls).
  double mean_position_m = 0.0;
  std::vector<double> along_m;  ///< each found point's coordinate along the wall
  std::vector<double> z_m;
  std::vector<double> deviation_m;
};

/// A nominal floor: z = nominal_m, probed on an nx x ny grid over x_lo..x_hi, y_lo..y_hi.
struct FloorSpec {
  double nominal_m = 0.0;
  double x_lo_m = 0.0, x_hi_m = 0.0, y_lo_m = 0.0, y_hi_m = 0.0;
  int nx = 10, ny = 3;
};

/// A floor's flatness: the range of the points' residuals about their least-squares plane (ISO
/// 12781's LSPL flatness, which bounds the minimum-zone flatness from above), and the mean deviation
/// from the nominal (> 0: material left).
struct FloorFlatness {
  int points = 0;
  double mean_m = 0.0;
  double flatness_m = 0.0;
  double rms_m = 0.0;  ///< residuals about the least-squares plane
};

/// A width between two walls (a slot, a pocket): the distance between their mean measured planes.
struct WidthMeasure {
  double width_m = 0.0;
  double nominal_m = 0.0;
  double error_m = 0.0;  ///< width - nominal
};

/// Thread safety: one thread at a time (its noise draws).
class PartProbe {
 public:
  /// `noise_m`: the probe's 1-sigma per point along the surface's normal (>= 0); `seed` its draws.
  /// Throws InputError for a noise that is negative or not finite.
  PartProbe(double noise_m, std::uint64_t seed);

  /// Throws InputError for an empty grid or one over 10 000 points a side, a range that is not
  /// increasing, or a search not positive.
  [[nodiscard]] WallProfile wall(const DexelStock& stock, const WallSpec& spec);
  /// Throws InputError for fewer than 3 points, over 10 000 a side, or a range that is not increasing.
  [[nodiscard]] FloorFlatness floor(const DexelStock& stock, const FloorSpec& spec);
  /// The width between walls `a` and `b` (measured), nominally their nominal planes apart.
  [[nodiscard]] static WidthMeasure width(const WallProfile& a, const WallSpec& a_spec, const WallProfile& b,
                                          const WallSpec& b_spec);

 private:
  [[nodiscard]] double noise() { return noise_m_ > 0.0 ? noise_m_ * normal_(rng_) : 0.0; }

  double noise_m_;
  std::mt19937_64 rng_;
  boost::random::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace deflex::cell
