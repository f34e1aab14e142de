// Sign choice of output quaternions.
#include "deflex/offline/detail/quaternion_sign.hpp"

#include <cmath>

namespace deflex {

Eigen::Quaterniond quaternion_near(const Pose& pose, const Eigen::Quaterniond& reference) {
  Eigen::Quaterniond q(pose.linear());
  q.normalize();
  if (q.dot(reference) < 0.0) {
    q.coeffs() = -q.coeffs();
  }
  return q;
}

Eigen::Quaterniond canonical_quaternion(const Pose& pose) {
  Eigen::Quaterniond q(pose.linear());
  q.normalize();
  // Components below 1e-12 count as zero, so rounding noise does not pick the sign.
  for (double c : {q.w(), q.x(), q.y(), q.z()}) {
    if (std::abs(c) > 1e-12) {
      if (c < 0.0) {
        q.coeffs() = -q.coeffs();
      }
      break;
    }
  }
  return q;
}

}  // namespace deflex
