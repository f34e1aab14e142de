// A milling cutter as the force model and the stock see it: diameter, flutes, helix and corner
// radius, from the command line's "diameter_mm=..,flutes=..,helix_deg=..[,corner_radius_mm=..]".
#pragma once

#include <string>

namespace deflex {

/// A rotating end mill: a cylinder of radius diameter_m / 2 with `flutes` equally spaced teeth on a
/// right-hand helix (left-hand for a left-hand cut, the mirror image), the bottom edge rounded by
/// `corner_radius_m` (0: flat end mill; diameter_m / 2: ball nose; in between: bull nose).
/// SI units. Validated by validate_cutter() before any model takes it.
struct Cutter {
  double diameter_m = 0.0;
  int flutes = 0;
  double helix_rad = 0.0;        ///< 0 (straight teeth) .. 60 deg
  double corner_radius_m = 0.0;  ///< 0 .. diameter_m / 2

  [[nodiscard]] double radius_m() const { return 0.5 * diameter_m; }
};

/// The accepted ranges (cutter.cpp says why): diameter 0.1 .. 300 mm, 1 .. 32 flutes, helix 0 .. 60
/// deg, corner radius 0 .. diameter / 2.
namespace cutter_limits {
inline constexpr double kMinDiameterMm = 0.1;
inline constexpr double kMaxDiameterMm = 300.0;
inline constexpr int kMaxFlutes = 32;
inline constexpr double kMaxHelixDeg = 60.0;
}  // namespace cutter_limits

/// Throws InputError naming the field ("cutter: flutes: 0 is not 1..32") when a value is outside
/// the ranges above or not finite. `what` prefixes the message (the option or file).
void validate_cutter(const Cutter& cutter, const std::string& what = "cutter");

/// Parses "diameter_mm=10,flutes=3,helix_deg=30[,corner_radius_mm=0.5]" (keys in any order,
/// diameter_mm and flutes required, helix_deg 0 and corner_radius_mm 0 when absent) and validates it.
/// Throws InputError quoting the spec and naming the key.
[[nodiscard]] Cutter parse_cutter_spec(const std::string& spec);

/// One line for humans: "10 mm, 3 flutes, helix 30 deg, flat end".
[[nodiscard]] std::string describe_cutter(const Cutter& cutter);

}  // namespace deflex
