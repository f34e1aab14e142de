// LDBB force device of the simulated cell (see ldbb_device.hpp).
#include "deflex/cell/ldbb_device.hpp"

#include <cmath>

namespace deflex::cell {

LdbbDevice::LdbbDevice(const LdbbConfig& config, const Vector3& nominal_pivot_m, double setpoint_n, std::uint64_t seed)
    : config_(config), pivot_(nominal_pivot_m + config.pivot_error_m), setpoint_n_(setpoint_n), rng_(seed) {}

void LdbbDevice::advance(double dt_s) {
  last_dt_s_ = dt_s;
  const double target = setpoint_n_ * (1.0 + config_.force_bias);
  state_n_ += (target - state_n_) * (1.0 - std::exp(-dt_s / config_.time_constant_s));
  t_ += dt_s;
}

void LdbbDevice::settle() { state_n_ = setpoint_n_ * (1.0 + config_.force_bias); }

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
  Vector3 force = (config_.push ? 1.0 : -1.0) * f * u;
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
