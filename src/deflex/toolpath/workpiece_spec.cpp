// The workpiece placement spec.
#include "deflex/toolpath/workpiece_spec.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/input_ranges.hpp"
#include "deflex/text/key_value_spec.hpp"

namespace deflex {

Pose parse_workpiece_spec(const std::string& spec) {
  static const std::vector<std::string> kKeys = {"x_mm", "y_mm", "z_mm", "qw", "qx", "qy", "qz"};
  const KeyValueSpec keys(spec, spec, kKeys);
  Pose pose = Pose::Identity();
  for (int k = 0; k < 3; ++k) {
    const std::string& key = kKeys[static_cast<std::size_t>(k)];
    if (!keys.has(key)) {
      keys.fail(fmt::format("key '{}' (the workpiece origin in the robot's base frame, mm) is required", key));
    }
    const double v = keys.number(key, 0.0);
    if (const auto bad = range_violation(v, range::kLengthMm)) {
      keys.fail(fmt::format("key '{}': {}", key, *bad));
    }
    pose.translation()[k] = v * 1e-3;
  }
  int given = 0;
  for (std::size_t k = 3; k < kKeys.size(); ++k) {
    given += keys.has(kKeys[k]) ? 1 : 0;
  }
  if (given != 0 && given != 4) {
    keys.fail("give all four of qw, qx, qy, qz (the workpiece's orientation in the base frame) or none");
  }
  if (given == 4) {
    const Eigen::Quaterniond q(keys.number("qw", 1.0), keys.number("qx", 0.0), keys.number("qy", 0.0),
                               keys.number("qz", 0.0));
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) <= kWorkpieceQuaternionTolerance)) {
      keys.fail(fmt::format("the quaternion (qw, qx, qy, qz) has norm {:.6f}, not 1 (within {})", norm,
                            kWorkpieceQuaternionTolerance));
    }
    pose.linear() = q.normalized().toRotationMatrix();
  }
  return pose;
}

}  // namespace deflex
