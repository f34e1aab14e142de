// Run-to-run drift of the simulated robot (see path_drift.hpp).
#include "deflex/cell/path_drift.hpp"

#include <cmath>

namespace deflex::cell {

PathDrift::PathDrift(const DriftConfig& config, std::uint64_t seed, double load_n) : config_(config), rng_(seed) {
  // Every draw is made whatever its size, so the run's other draws do not depend on this effect.
  for (int i = 0; i < 3; ++i) offset_m_[i] = config.offset_m * normal_(rng_);
  for (int i = 0; i < 3; ++i) rotation_rad_[i] = config.rotation_rad * normal_(rng_);
  // The wander starts from its stationary distribution: the run begins at an arbitrary time.
  for (int i = 0; i < 3; ++i) wander_m_[i] = config.wander_m * normal_(rng_);
  // The motors' extra heat under load: proportional to the load squared.
  const double r = config.load_reference_n > 0.0 ? load_n / config.load_reference_n : 0.0;
  for (int i = 0; i < 3; ++i) load_offset_m_[i] = config.load_offset_m * r * r * normal_(rng_);
  active_ = config.offset_m > 0 || config.rotation_rad > 0 || config.wander_m > 0 || config.load_offset_m > 0;
}

PathDrift::PathDrift(const DriftConfig& config, std::uint64_t seed, const PathDrift& previous, double elapsed_s,
                     double load_n)
    : PathDrift(config, seed, load_n) {
  // The fresh draws of the constructor above are the innovations: x' = a x + sqrt(1 - a^2) draw.
  const double a = config.offset_time_s > 0.0 ? std::exp(-std::max(0.0, elapsed_s) / config.offset_time_s) : 0.0;
  const double s = std::sqrt(1.0 - a * a);
  offset_m_ = a * previous.offset_m_ + s * offset_m_;
  rotation_rad_ = a * previous.rotation_rad_ + s * rotation_rad_;
}

void PathDrift::advance(double dt_s) {
  if (config_.wander_m <= 0.0) return;
  // A run steps by the same servo tick throughout: the step's factors are kept for it.
  if (dt_s != step_dt_s_) {
    step_dt_s_ = dt_s;
    step_a_ = std::exp(-dt_s / config_.wander_time_s);
    step_s_ = config_.wander_m * std::sqrt(1.0 - step_a_ * step_a_);
  }
  for (int i = 0; i < 3; ++i) wander_m_[i] = step_a_ * wander_m_[i] + step_s_ * normal_(rng_);
}

}  // namespace deflex::cell
