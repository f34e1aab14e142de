// Force sensor and DAQ of the simulated cell (see force_sensor.hpp).
#include "deflex/cell/force_sensor.hpp"

#include <cmath>

namespace deflex::cell {

ForceSensorDaq::ForceSensorDaq(const SensorConfig& sensor, const ToolConfig& tool, std::uint64_t seed,
                               std::uint64_t unit_seed)
    : config_(sensor), tool_(tool), rng_(unit_seed) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  crosstalk_ = Matrix3::Identity();
  Matrix3 residual = Matrix3::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) {
        crosstalk_(i, j) = sensor.crosstalk * uniform(rng_);
      }
      residual(i, j) = sensor.crosstalk_calibration_residual * uniform(rng_);
    }
  }
  // The sheet's sensitivities are off by the calibration's uncertainty; the user decouples with the
  // sheet, so the reading keeps this error (drawn whatever its size: the other draws stay the same).
  for (int i = 0; i < 3; ++i) sensitivity_[i] = 1.0 + sensor.sensitivity_error * normal_(rng_);
  response_ = crosstalk_ * sensitivity_.asDiagonal();
  flange_R_sensor_ = Eigen::AngleAxisd(sensor.misalignment_rad, Vector3::UnitZ()).toRotationMatrix();
  calibration_.decoupling = crosstalk_.inverse() * (Matrix3::Identity() + residual);
  // The force channels' response to moments: a property of the spring body, drawn after the other
  // unit draws so they stay what they were.
  const double per_nm = sensor.moment_crosstalk * sensor.nominal_lateral_force_n / sensor.nominal_moment_nm;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) moment_crosstalk_(i, j) = per_nm * uniform(rng_);
  }
  // The point of origin is the sensor's centre; the end effector's length counts from its top.
  lever_m_ = Vector3(0.0, 0.0, tool.ee_length_m + 0.5 * sensor.height_m);
  // What the drawings and a hand measurement say about the mounting.
  Vector3 cog_error;
  for (int i = 0; i < 3; ++i) cog_error[i] = normal_(rng_);
  calibration_.ee_cog_m = tool.ee_cog_m + sensor.sheet_cog_error_m * cog_error;
  calibration_.height_m = sensor.height_m + sensor.sheet_height_error_m * normal_(rng_);
  rng_.reseed(seed, false);  // noise and zero drift: this run's own
  normal_.reset();
  for (int i = 0; i < 3; ++i) zero_drift_n_per_s_[i] = sensor.zero_drift_n / 600.0 * normal_(rng_);
  if (sensor.fast_noise) rng_.reseed(seed ^ kFastNoiseSalt, true);
  calibration_.ee_mass_kg = tool.ee_mass_kg * (1.0 + sensor.gravity_mass_error);
}

Vector3 ForceSensorDaq::sample(const Vector3& process_force_base_n, const Matrix3& base_R_flange, double t_s) {
  const Vector3 weight_base(0.0, 0.0, -tool_.ee_mass_kg * kGravity);
  const Matrix3 sensor_R_base = (base_R_flange * flange_R_sensor_).transpose();
  const Vector3 f_sensor = sensor_R_base * (process_force_base_n + weight_base);
  Vector3 noise(normal_(rng_), normal_(rng_), normal_(rng_));
  Vector3 reading = response_ * f_sensor + config_.bias_n + zero_drift_n_per_s_ * t_s + config_.noise_n * noise;
  if (config_.moment_crosstalk > 0.0) {
    // The moments about the point of origin of the process force (at the TCP) and of the end
    // effector's weight (at its centre of gravity); beyond the nominal moment the response grows.
    const Vector3 cog = tool_.ee_cog_m + Vector3(0.0, 0.0, 0.5 * config_.height_m);
    Vector3 m = lever_m_.cross(sensor_R_base * process_force_base_n) + cog.cross(sensor_R_base * weight_base);
    for (int j = 0; j < 3; ++j) {
      const double over = std::abs(m[j]) / config_.nominal_moment_nm - 1.0;
      if (over > 0.0) m[j] *= 1.0 + config_.moment_overload_growth * over;
    }
    reading += moment_crosstalk_ * m;
  }
  return reading;
}

}  // namespace deflex::cell
