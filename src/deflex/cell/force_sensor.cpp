// Force sensor and DAQ of the simulated cell (see force_sensor.hpp).
#include "deflex/cell/force_sensor.hpp"

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
  flange_R_sensor_ = Eigen::AngleAxisd(sensor.misalignment_rad, Vector3::UnitZ()).toRotationMatrix();
  calibration_.decoupling = crosstalk_.inverse() * (Matrix3::Identity() + residual);
  rng_.seed(seed);  // noise and zero drift: this run's own
  normal_.reset();
  for (int i = 0; i < 3; ++i) zero_drift_n_per_s_[i] = sensor.zero_drift_n / 600.0 * normal_(rng_);
  calibration_.bias_n = sensor.bias_n;  // tared at a static pose: the bias itself is known
  calibration_.ee_mass_kg = tool.ee_mass_kg * (1.0 + sensor.gravity_mass_error);
  calibration_.ee_cog_m = tool.ee_cog_m;
}

Vector3 ForceSensorDaq::sample(const Vector3& process_force_base_n, const Matrix3& base_R_flange, double t_s) {
  const Vector3 weight_base(0.0, 0.0, -tool_.ee_mass_kg * kGravity);
  const Vector3 f_sensor = (base_R_flange * flange_R_sensor_).transpose() * (process_force_base_n + weight_base);
  Vector3 noise(normal_(rng_), normal_(rng_), normal_(rng_));
  return crosstalk_ * sensitivity_.asDiagonal() * f_sensor + config_.bias_n + zero_drift_n_per_s_ * t_s +
         config_.noise_n * noise;
}

}  // namespace deflex::cell
