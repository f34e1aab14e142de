// LDBB force device of the simulated cell (see ldbb_device.hpp).
#include "deflex/cell/ldbb_device.hpp"

#include <algorithm>
#include <cmath>

namespace deflex::cell {
namespace {

// Below this speed across the bar (m/s) the sockets' friction grows with the speed instead of
// standing at its sliding level: Coulomb's law regularised, so that an arm standing still (its drift
// wanders by micrometres a tick) meets no full friction in an arbitrary direction, and the friction
// is a continuous function of where the arm is for the tick's solve. A twentieth of the slowest
// speed of the protocol (10 mm/s): every lap is at the sliding level.
constexpr double kBallSlidingSpeed = 5e-4;
// The share of a stick-slip tooth over which the seal sticks; it slips over the rest.
constexpr double kStickFraction = 0.9;

}  // namespace

LdbbDevice::LdbbDevice(const LdbbConfig& config, const Vector3& nominal_pivot_m, double setpoint_n, std::uint64_t seed)
    : config_(config), pivot_(nominal_pivot_m + config.pivot_error_m), setpoint_n_(setpoint_n), rng_(seed) {
  // The seal's friction level of this run (the bar is pressurised afresh for every run).
  seal_friction_ = std::max(0.0, config.seal_friction + config.seal_friction_spread * normal_(rng_));
  if (config.stick_slip_travel_m > 0.0) per_tooth_ = 1.0 / config.stick_slip_travel_m;
  if (config.noise > 0.0) noise_draw_ = normal_(rng_);  // the noise's stationary start
}

void LdbbDevice::advance(double dt_s) {
  // A run steps by the same servo tick throughout: the chamber's factor for it is kept.
  if (dt_s != step_dt_s_) {
    step_dt_s_ = dt_s;
    step_a_ = std::exp(-dt_s / config_.time_constant_s);
  }
  const double target = setpoint_n_;
  state_n_ += (target - state_n_) * (1.0 - step_a_);
  t_ += dt_s;
  ripple_factor_ = 1.0 + config_.ripple * std::sin(2.0 * kPi * config_.ripple_hz * t_);
  if (config_.noise > 0.0) {
    // The regulator's noise reaches the force through the chamber's first-order response: an
    // Ornstein-Uhlenbeck process of the bar's time constant and a stationary 1-sigma of `noise` (exact
    // step), not a new draw every servo tick, which no air volume passes.
    noise_draw_ = step_a_ * noise_draw_ + std::sqrt(1.0 - step_a_ * step_a_) * normal_(rng_);
  }
}

void LdbbDevice::settle() { state_n_ = setpoint_n_; }

double LdbbDevice::magnitude_n() const {
  double f = state_n_ * ripple_factor_;
  if (config_.noise > 0.0) {
    f += state_n_ * config_.noise * noise_draw_;
  }
  return f;
}

double LdbbDevice::stick_slip_at(double length_m) const {
  if (!(config_.stick_slip > 0.0 && config_.stick_slip_travel_m > 0.0)) return 1.0;
  // The seal sticks while the force builds with the piston's travel and slips back once per tooth:
  // a sawtooth between -1/2 and +1/2 of the amplitude, rising over nine tenths of the tooth and
  // slipping over the last tenth (a slip takes some travel, so the force stays a continuous function
  // of where the arm is).
  const double travel = travel_m_ + (last_length_m_ >= 0.0 ? std::abs(length_m - last_length_m_) : 0.0);
  const double phase = travel * per_tooth_;
  const double x = phase - std::floor(phase);
  const double shape = x < kStickFraction ? x / kStickFraction : (1.0 - x) / (1.0 - kStickFraction);
  return 1.0 + config_.stick_slip * (shape - 0.5);
}

double LdbbDevice::seal_at(double length_m) const {
  // The piston follows the bar's length; the seal's friction builds over its pre-sliding travel
  // (elastic seal lips) up to its sliding level, against the piston's motion.
  if (last_length_m_ < 0.0 || seal_friction_ <= 0.0) return seal_n_;
  const double limit = seal_friction_ * state_n_;
  const double travel = std::max(config_.seal_presliding_m, 1e-9);
  return std::clamp(seal_n_ + limit / travel * (length_m - last_length_m_), -limit, limit);
}

Wrench LdbbDevice::wrench_at(const TcpMotion& motion) const {
  const Vector3 bar = motion.position_m - pivot_;
  const double length = bar.norm();
  const Vector3 u = bar / length;
  double f = magnitude_n() * stick_slip_at(length);
  const double sign = config_.push ? 1.0 : -1.0;
  f -= sign * seal_at(length);
  Vector3 force = sign * f * u;
  // The ball sockets at both ends turn as the bar sweeps; their friction torque mu*F*r at each end
  // appears at the TCP as a force across the bar, against the motion.
  const Vector3& v = motion.velocity_m_s;
  const Vector3 v_perp = v - u * u.dot(v);
  const double speed = v_perp.norm();
  if (config_.ball_friction > 0.0 && speed > 0.0) {
    force -= v_perp / std::max(speed, kBallSlidingSpeed) *
             (2.0 * config_.ball_friction * f * config_.ball_radius_m / length);
  }
  Wrench w;
  w << force, Vector3::Zero();
  return w;
}

void LdbbDevice::commit(const TcpMotion& motion) {
  const double length = (motion.position_m - pivot_).norm();
  seal_n_ = seal_at(length);
  if (last_length_m_ >= 0.0) travel_m_ += std::abs(length - last_length_m_);
  last_length_m_ = length;
}

Wrench LdbbDevice::wrench(const Vector3& tcp_m, const Vector3& tcp_velocity_m_s) {
  TcpMotion motion;
  motion.position_m = tcp_m;
  motion.velocity_m_s = tcp_velocity_m_s;
  Wrench w = wrench_at(motion);
  commit(motion);
  return w;
}

}  // namespace deflex::cell
