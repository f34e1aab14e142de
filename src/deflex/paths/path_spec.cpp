// Parser of circle and line path specifications.
#include "deflex/paths/path_spec.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/paths/detail/pose_path_csv.hpp"
#include "deflex/text/key_value_spec.hpp"

namespace deflex {
namespace {

Vector3 vector_of(const KeyValueSpec& keys, const std::string& key, const Vector3& fallback, double scale) {
  if (!keys.has(key)) {
    return fallback;
  }
  const auto v = keys.numbers(key, 3);
  return Vector3(v[0], v[1], v[2]) * scale;
}

}  // namespace

CirclePath default_circle() {
  CirclePath c;
  c.centre_m = Vector3(1.5, 0.0, 1.0);
  c.radius_m = 0.1;
  c.normal = Vector3::UnitZ();
  c.start_angle_rad = 0.0;
  c.clockwise = false;
  c.points = 81;
  c.start_reference = Vector3::UnitX();
  return c;
}

CirclePath parse_circle_spec(const std::string& spec) {
  const KeyValueSpec keys(spec, spec,
                          {"centre_mm", "radius_mm", "normal", "start_deg", "direction", "points", "reference"});
  CirclePath c = default_circle();
  c.centre_m = vector_of(keys, "centre_mm", c.centre_m, 1e-3);
  c.radius_m = keys.number("radius_mm", c.radius_m * 1e3) * 1e-3;
  if (c.radius_m <= 0.0) {
    keys.fail("key 'radius_mm': must be positive");
  }
  c.normal = vector_of(keys, "normal", c.normal, 1.0);
  if (c.normal.norm() < 1e-12) {
    keys.fail("key 'normal': must not be zero");
  }
  c.start_reference = vector_of(keys, "reference", c.start_reference, 1.0);
  c.start_angle_rad = deg_to_rad(keys.number("start_deg", 0.0));
  if (keys.has("direction")) {
    const std::string& d = keys.text("direction");
    if (d != "ccw" && d != "cw") {
      keys.fail(fmt::format("key 'direction': '{}' is neither ccw nor cw", d));
    }
    c.clockwise = d == "cw";
  }
  c.points = keys.integer("points", c.points);
  if (c.points < 3 || c.points > kMaxCirclePoints) {
    keys.fail(fmt::format("key 'points': a circle needs 3..{} points", kMaxCirclePoints));
  }
  return c;
}

LinePath parse_line_spec(const std::string& spec) {
  const KeyValueSpec keys(spec, spec, {"start_mm", "end_mm", "points"});
  if (!keys.has("start_mm") || !keys.has("end_mm")) {
    keys.fail("a line needs start_mm=X;Y;Z and end_mm=X;Y;Z");
  }
  LinePath l;
  l.start_m = vector_of(keys, "start_mm", Vector3::Zero(), 1e-3);
  l.end_m = vector_of(keys, "end_mm", Vector3::Zero(), 1e-3);
  l.points = keys.integer("points", 2);
  if (l.points < 2 || l.points > kMaxPathPoints) {
    keys.fail(fmt::format("key 'points': a line needs 2..{} points", kMaxPathPoints));
  }
  return l;
}

}  // namespace deflex
