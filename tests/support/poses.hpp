// A joint pose written in degrees, as the tests state their poses.
#pragma once

#include "deflex/model/types.hpp"

namespace deflex::test {

/// The six joints (a, b, c, d, e, f) in degrees, as a JointVector in radians.
inline JointVector pose_deg(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << a, b, c, d, e, f;
  return q * (kPi / 180.0);
}

}  // namespace deflex::test
