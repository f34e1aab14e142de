// LDBB force device of the simulated cell (see ldbb_device.hpp).
#include "deflex/cell/ldbb_device.hpp"

#include <algorithm>
#include <cmath>

namespace deflex::cell {

LdbbDevice::LdbbDevice(const LdbbConfig& config, const Vector3& nominal_pivot_m, double setpoint_n, std::uint64_t seed)
    : config_(config), pivot_(nominal_pivot_m + config.pivot_error_m), setpoint_n_(setpoint_n), rng_(seed) {
  // The seal's friction level of this run (the bar is pressurised afresh for every run).
  seal_friction_ = std::max(0.0, config.seal_friction + config.seal_friction_spread * normal_(rng_));
}

void LdbbDevice::advance(double dt_s) {
  last_dt_s_ = dt_s;
  const double target = setpoint_n_;
  state_n_ += (target - state_n_) * (1.0 - std::exp(-dt_s / config_.time_constant_s));
  t_ += dt_s;
}

void LdbbDevice::settle() { state_n_ = setpoint_n_; }

double LdbbDevice::magnitude_n() {
  double f = state_n_ * (1.0 + config_.ripple * std::sin(2.0 * kPi * config_.ripple_hz * t_));
  if (config_.noise > 0.0) {
    f += state_n_ * config_.noise * normal_(rng_);
  }
  return f;
}

Wrench LdbbDevice::wrench(const Vector3& tcp_m, const Vector3& tcp_velocity_m_s) {
  const Vector3 bar = tcp_m - pivot_;
  const double length = bar.norm();
  const Vector3 u = bar / length;
  double f = magnitude_n();
  if (config_.stick_slip > 0.0 && config_.stick_slip_travel_m > 0.0) {
    // The seal sticks while the force builds and slips back once per tooth of travel: a sawtooth
    // between -1/2 and +1/2 of the amplitude.
    const double phase = travel_m_ / config_.stick_slip_travel_m;
    f *= 1.0 + config_.stick_slip * (phase - std::floor(phase) - 0.5);
  }
  // The piston follows the bar's length; the seal's friction builds over its pre-sliding travel
  // (elastic seal lips) up to its sliding level, against the piston's motion.
  const double sign = config_.push ? 1.0 : -1.0;
  if (last_length_m_ >= 0.0 && seal_friction_ > 0.0) {
    const double limit = seal_friction_ * state_n_;
    const double travel = std::max(config_.seal_presliding_m, 1e-9);
    seal_n_ = std::clamp(seal_n_ + limit / travel * (length - last_length_m_), -limit, limit);
  }
  last_length_m_ = length;
  f -= sign * seal_n_;
  Vector3 force = sign * f * u;
  // The ball sockets at both ends turn as the bar sweeps; their friction torque mu*F*r at each end
  // appears at the TCP as a force across the bar, against the motion.
  travel_m_ += tcp_velocity_m_s.norm() * last_dt_s_;
  const Vector3 v_perp = tcp_velocity_m_s - u * u.dot(tcp_velocity_m_s);
  const double speed = v_perp.norm();
  if (config_.ball_friction > 0.0 && speed > 1e-9) {
    force -= v_perp / speed * (2.0 * config_.ball_friction * f * config_.ball_radius_m / length);
  }
  Wrench w;
  w << force, Vector3::Zero();
  return w;
}

}  // namespace deflex::cell
