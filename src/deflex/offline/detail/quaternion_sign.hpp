// Choosing the sign of output quaternions. q and -q are the same rotation; written files read
// better (and interpolate the short way) when the sign does not flip between neighbouring points or
// between a desired and a commanded pose.
#pragma once

#include "deflex/model/types.hpp"

namespace deflex {

/// Rotation of `pose` as a unit quaternion with the sign that makes its dot product with
/// `reference` non-negative.
[[nodiscard]] Eigen::Quaterniond quaternion_near(const Pose& pose, const Eigen::Quaterniond& reference);

/// Canonical sign for a first point: the first non-zero component of (w, x, y, z) positive.
[[nodiscard]] Eigen::Quaterniond canonical_quaternion(const Pose& pose);

}  // namespace deflex
