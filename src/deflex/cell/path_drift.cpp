// Run-to-run drift of the simulated robot (see path_drift.hpp).
#include "deflex/cell/path_drift.hpp"

#include <cmath>

namespace deflex::cell {

PathDrift::PathDrift(const DriftConfig& config, std::uint64_t seed) : config_(config), rng_(seed) {
  // Every draw is made whatever its size, so the run's other draws do not depend on this effect.
  for (int i = 0; i < 3; ++i) offset_m_[i] = config.offset_m * normal_(rng_);
  for (int i = 0; i < 3; ++i) rotation_rad_[i] = config.rotation_rad * normal_(rng_);
  // The wander starts from its stationary distribution: the run begins at an arbitrary time.
  for (int i = 0; i < 3; ++i) wander_m_[i] = config.wander_m * normal_(rng_);
  active_ = config.offset_m > 0 || config.rotation_rad > 0 || config.wander_m > 0;
}

void PathDrift::advance(double dt_s) {
  if (config_.wander_m <= 0.0) return;
  const double a = std::exp(-dt_s / config_.wander_time_s);
  const double s = config_.wander_m * std::sqrt(1.0 - a * a);
  for (int i = 0; i < 3; ++i) wander_m_[i] = a * wander_m_[i] + s * normal_(rng_);
}

}  // namespace deflex::cell
