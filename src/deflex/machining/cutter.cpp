// The cutter's specification and its checks.
//
// The ranges admit every cutter a robot spindle carries and refuse what is a typo or a unit slip:
// micro end mills start at 0.1 mm, the largest face mills on robot spindles are around 160 mm
// (300 mm leaves room); face mills carry up to about 20 inserts (32 flutes); helix angles of end
// mills run from 0 (straight teeth, inserts) to 45-55 deg (high-helix finishing mills), so 60 deg is
// the top. A corner radius above half the diameter is not a shape.
#include "deflex/machining/cutter.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/model/types.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/key_value_spec.hpp"

namespace deflex {

void validate_cutter(const Cutter& cutter, const std::string& what) {
  using namespace cutter_limits;
  const double d_mm = cutter.diameter_m * 1e3;
  if (!std::isfinite(d_mm) || d_mm < kMinDiameterMm || d_mm > kMaxDiameterMm) {
    throw InputError(
        fmt::format("{}: diameter_mm: {:g} mm is outside {:g}..{:g} mm", what, d_mm, kMinDiameterMm, kMaxDiameterMm));
  }
  if (cutter.flutes < 1 || cutter.flutes > kMaxFlutes) {
    throw InputError(fmt::format("{}: flutes: {} is not 1..{} (a cutter without flutes does not cut)", what,
                                 cutter.flutes, kMaxFlutes));
  }
  const double helix_deg = rad_to_deg(cutter.helix_rad);
  if (!std::isfinite(helix_deg) || helix_deg < 0.0 || helix_deg > kMaxHelixDeg) {
    throw InputError(fmt::format("{}: helix_deg: {:g} deg is outside 0..{:g} deg", what, helix_deg, kMaxHelixDeg));
  }
  const double r_mm = cutter.corner_radius_m * 1e3;
  if (!std::isfinite(r_mm) || r_mm < 0.0 || r_mm > 0.5 * d_mm * (1.0 + 1e-12)) {
    throw InputError(
        fmt::format("{}: corner_radius_mm: {:g} mm is outside 0..{:g} mm (half the diameter)", what, r_mm, 0.5 * d_mm));
  }
}

Cutter parse_cutter_spec(const std::string& spec) {
  const KeyValueSpec keys(spec, spec, {"diameter_mm", "flutes", "helix_deg", "corner_radius_mm"});
  for (const char* required : {"diameter_mm", "flutes"}) {
    if (!keys.has(required)) {
      keys.fail(fmt::format("key '{}' is required", required));
    }
  }
  Cutter c;
  c.diameter_m = keys.number("diameter_mm", 0.0) * 1e-3;
  c.flutes = keys.integer("flutes", 0);
  c.helix_rad = deg_to_rad(keys.number("helix_deg", 0.0));
  c.corner_radius_m = keys.number("corner_radius_mm", 0.0) * 1e-3;
  validate_cutter(c, fmt::format("spec '{}'", spec));
  return c;
}

std::string describe_cutter(const Cutter& cutter) {
  const double r = cutter.corner_radius_m;
  std::string end = "flat end";
  if (r > 0.0) {
    end = std::abs(r - cutter.radius_m()) < 1e-9 ? "ball nose" : fmt::format("corner radius {:g} mm", r * 1e3);
  }
  return fmt::format("{:g} mm, {} flute{}, helix {:g} deg, {}", cutter.diameter_m * 1e3, cutter.flutes,
                     cutter.flutes == 1 ? "" : "s", rad_to_deg(cutter.helix_rad), end);
}

}  // namespace deflex
