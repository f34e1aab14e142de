// Run-to-run drift and path repeatability of the simulated robot: each run is displaced by its own
// small rigid motion (thermal drift of a warmed-up arm between runs; a loaded run's motors warm more,
// so it gets an extra offset growing with its load) plus a slow random wander within the run (path
// repeatability). Draws come from the run's own seed, so the unloaded reference
// and each loaded run wander independently, as different runs on a real cell do.
#pragma once

#include <cstdint>
#include <random>

#include <boost/random/normal_distribution.hpp>

#include "deflex/cell/cell_config.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (advance() draws from its own random generator).
class PathDrift {
 public:
  /// `load_n`: the run's process load (its motors warm more: the load offset of DriftConfig).
  PathDrift(const DriftConfig& config, std::uint64_t seed, double load_n = 0.0);
  /// A run that starts `elapsed_s` after `previous` started, in the same session: its rigid offset and
  /// rotation are the previous run's evolved over that time (the thermal drift is slow, an
  /// Ornstein-Uhlenbeck process of correlation time offset_time_s); its wander is its own.
  PathDrift(const DriftConfig& config, std::uint64_t seed, const PathDrift& previous, double elapsed_s,
            double load_n = 0.0);

  /// Advances the wander by dt (exact Ornstein-Uhlenbeck step: stationary 1-sigma wander_m per axis,
  /// autocorrelation exp(-lag / wander_time_s)).
  void advance(double dt_s);
  /// The drifted position of a TCP at p_base_m (m, base frame): p + offset + rotation x p + wander.
  [[nodiscard]] Vector3 apply(const Vector3& p_base_m) const {
    return p_base_m + offset_m_ + load_offset_m_ + rotation_rad_.cross(p_base_m) + wander_m_;
  }
  [[nodiscard]] const Vector3& offset_m() const { return offset_m_; }
  [[nodiscard]] const Vector3& rotation_rad() const { return rotation_rad_; }
  [[nodiscard]] const Vector3& wander_m() const { return wander_m_; }
  [[nodiscard]] const Vector3& load_offset_m() const { return load_offset_m_; }
  [[nodiscard]] bool active() const { return active_; }

 private:
  DriftConfig config_;
  std::mt19937_64 rng_;
  boost::random::normal_distribution<double> normal_{0.0, 1.0};
  Vector3 offset_m_ = Vector3::Zero();
  Vector3 rotation_rad_ = Vector3::Zero();
  Vector3 wander_m_ = Vector3::Zero();
  Vector3 load_offset_m_ = Vector3::Zero();
  bool active_ = false;
  double step_dt_s_ = -1.0, step_a_ = 0.0, step_s_ = 0.0;  // advance()'s factors for its last step
};

}  // namespace deflex::cell
