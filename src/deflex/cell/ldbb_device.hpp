// The Loaded Double Ball Bar of the simulated cell (paper, Figure 4): a bar from a table pivot to the
// TCP ball, pneumatic force with a set-point, first-order response, ripple and noise (through the same
// response), and the force
// errors neither the bar's report nor the offline force model know: the cylinder seal's friction
// against the piston's motion (with its pre-sliding and its level from run to run), its stick-slip
// as the piston slides,
// the pivot's position error, and ball-joint friction that opposes the bar's rotation and so depends
// on the direction of travel. Its force depends on where the arm is (the bar's length strokes the
// piston), so it is a ProcessForce the tick's coupled solve settles together with the arm.
#pragma once

#include <cstdint>
#include <random>

#include <boost/random/normal_distribution.hpp>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/process_force.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (its state and its own random generator).
class LdbbDevice final : public ProcessForce {
 public:
  /// `nominal_pivot_m`: the pivot the force model assumes; the true pivot adds config.pivot_error_m.
  LdbbDevice(const LdbbConfig& config, const Vector3& nominal_pivot_m, double setpoint_n, std::uint64_t seed);

  /// Advances the pneumatic force by dt (s): first-order response to the set-point, the noise through
  /// the same response.
  void advance(double dt_s) override;
  /// Sets the pneumatic force to its settled value (skip the build-up).
  void settle();
  /// Force magnitude this tick, N (first-order state plus ripple and the tick's noise).
  [[nodiscard]] double magnitude_n() const;
  /// Wrench on the TCP ball (base frame, moment about the TCP = 0) with the TCP moving as `motion`:
  /// magnitude along the bar from the true pivot less what the seal holds once the piston has
  /// followed the bar to this length, plus ball friction opposing the TCP's motion. Changes nothing.
  [[nodiscard]] Wrench wrench_at(const TcpMotion& motion) const override;
  /// The piston has followed the bar to the TCP's position: the seal's friction and the piston's
  /// travel the stick-slip counts move on.
  void commit(const TcpMotion& motion) override;
  /// The tick with the TCP at `tcp_m` moving at `tcp_velocity_m_s`, whatever the arm does: wrench_at
  /// then commit (the bar alone, as its tests drive it).
  [[nodiscard]] Wrench wrench(const Vector3& tcp_m, const Vector3& tcp_velocity_m_s);
  [[nodiscard]] const Vector3& true_pivot_m() const { return pivot_; }
  [[nodiscard]] double time_s() const { return t_; }
  /// This run's seal friction level (fraction of the pneumatic force the seal can hold).
  [[nodiscard]] double seal_friction() const { return seal_friction_; }
  /// What the seal holds now (N, positive against the piston extending).
  [[nodiscard]] double seal_force_n() const { return seal_n_; }

 private:
  /// What the seal holds once the piston has followed the bar to `length_m` from its last length.
  [[nodiscard]] double seal_at(double length_m) const;
  /// The stick-slip's factor on the force once the piston has followed the bar to `length_m`.
  [[nodiscard]] double stick_slip_at(double length_m) const;

  LdbbConfig config_;
  Vector3 pivot_;
  double setpoint_n_;
  double state_n_ = 0.0;
  double noise_draw_ = 0.0;     // the pneumatic noise now, in units of its 1-sigma
  double ripple_factor_ = 1.0;  // this tick's 1 + ripple sin(2 pi f t)
  double t_ = 0.0;
  double step_dt_s_ = -1.0, step_a_ = 0.0;  // advance()'s chamber factor exp(-dt / tau) for its last step
  double travel_m_ = 0.0;                   // the piston's travel in the cylinder, either way, for the stick-slip
  double per_tooth_ = 0.0;                  // stick-slip teeth per metre of that travel
  double seal_friction_ = 0.0;
  double seal_n_ = 0.0;
  double last_length_m_ = -1.0;  // the bar's length at the last commit (negative: none yet)
  std::mt19937_64 rng_;
  boost::random::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace deflex::cell
