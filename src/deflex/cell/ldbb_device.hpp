// The Loaded Double Ball Bar of the simulated cell (paper, Figure 4): a bar from a table pivot to the
// TCP ball, pneumatic force with a set-point, first-order response, ripple and noise, and the force
// errors neither the bar's report nor the offline force model know: the cylinder seal's friction
// against the piston's motion (with its pre-sliding and its level from run to run), its stick-slip,
// the pivot's position error, and ball-joint friction that opposes the bar's rotation and so depends
// on the direction of travel.
#pragma once

#include <cstdint>
#include <random>

#include <boost/random/normal_distribution.hpp>

#include "deflex/cell/cell_config.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (its state and its own random generator).
class LdbbDevice {
 public:
  /// `nominal_pivot_m`: the pivot the force model assumes; the true pivot adds config.pivot_error_m.
  LdbbDevice(const LdbbConfig& config, const Vector3& nominal_pivot_m, double setpoint_n, std::uint64_t seed);

  /// Advances the pneumatic force by dt (s): first-order response to the set-point.
  void advance(double dt_s);
  /// Sets the pneumatic force to its settled value (skip the build-up).
  void settle();
  /// Force magnitude now, N (first-order state plus ripple and noise).
  [[nodiscard]] double magnitude_n();
  /// Wrench on the TCP ball (base frame, moment about the TCP = 0): magnitude along the bar from
  /// the true pivot less what the seal holds, plus ball friction opposing the TCP's motion
  /// (`tcp_velocity_m_s`). Each call is the next tick: the piston follows the bar's length.
  [[nodiscard]] Wrench wrench(const Vector3& tcp_m, const Vector3& tcp_velocity_m_s);
  [[nodiscard]] const Vector3& true_pivot_m() const { return pivot_; }
  [[nodiscard]] double time_s() const { return t_; }
  /// This run's seal friction level (fraction of the pneumatic force the seal can hold).
  [[nodiscard]] double seal_friction() const { return seal_friction_; }
  /// What the seal holds now (N, positive against the piston extending).
  [[nodiscard]] double seal_force_n() const { return seal_n_; }

 private:
  LdbbConfig config_;
  Vector3 pivot_;
  double setpoint_n_;
  double state_n_ = 0.0;
  double t_ = 0.0;
  double travel_m_ = 0.0;  // the TCP's path travel, for the stick-slip
  double last_dt_s_ = 0.0;
  double seal_friction_ = 0.0;
  double seal_n_ = 0.0;
  double last_length_m_ = -1.0;  // the bar's length at the last call (negative: none yet)
  std::mt19937_64 rng_;
  boost::random::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace deflex::cell
