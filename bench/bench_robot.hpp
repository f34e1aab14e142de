// The robot and the configurations the model benchmarks share: the built-in IRB6700 and joint
// values drawn uniformly inside its limits (std::mt19937_64, seed 1), so every benchmark of the same
// size works on the same configurations.
#pragma once

#include <random>
#include <vector>

#include "deflex/robotfile/robot_io.hpp"

namespace deflex::bench {

inline const RobotModel& irb6700() {
  static const RobotModel m = builtin_irb6700();
  return m;
}

inline std::vector<JointVector> random_configurations(int count) {
  std::mt19937_64 rng(1);
  std::vector<JointVector> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int s = 0; s < count; ++s) {
    JointVector q(irb6700().dof());
    for (int i = 0; i < q.size(); ++i) {
      q[i] = std::uniform_real_distribution<double>(irb6700().lower_limits()[i], irb6700().upper_limits()[i])(rng);
    }
    out.push_back(q);
  }
  return out;
}

}  // namespace deflex::bench
