// The three-component force sensor and its DAQ (HBM MSC10-class on an NI-9237-class bridge module):
// it measures the force between flange and end effector in its own frame, i.e. the process force
// plus the end effector's weight, through a crosstalk matrix, with bias and noise, at the DAQ rate.
// It also says what a calibrated user would know about it (the decoupling matrix, the end
// effector's mass) with the calibration's residual errors.
#pragma once

#include <cstdint>
#include <random>

#include <boost/random/normal_distribution.hpp>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/noise_engine.hpp"

namespace deflex::cell {

/// What the sensor's sheet and the mounting's drawings give the user (close to, never exactly, the
/// truth). No bias: the user tares the mounted sensor (its zero moves when it is bolted down).
struct SensorCalibration {
  Matrix3 decoupling = Matrix3::Identity();  ///< measured -> decoupled, sensor frame
  double ee_mass_kg = 0.0;
  Vector3 ee_cog_m = Vector3::Zero();
  double height_m = 0.0;  ///< flange to the sensor's top, as measured
};

/// Thread safety: one thread at a time (sample() draws from its own random generator).
class ForceSensorDaq {
 public:
  /// `seed` draws the noise of this run; `unit_seed` draws what belongs to the physical sensor (its
  /// crosstalk, the calibration's residual and the true sensitivities), the same in every run.
  ForceSensorDaq(const SensorConfig& sensor, const ToolConfig& tool, std::uint64_t seed, std::uint64_t unit_seed);
  ForceSensorDaq(const SensorConfig& sensor, const ToolConfig& tool, std::uint64_t seed)
      : ForceSensorDaq(sensor, tool, seed, seed) {}

  /// One DAQ sample (N, sensor frame = flange frame) for the process force on the TCP (base frame)
  /// at the flange orientation base_R_flange, taken t_s after the sensor was tared (its zero drifts).
  [[nodiscard]] Vector3 sample(const Vector3& process_force_base_n, const Matrix3& base_R_flange, double t_s = 0.0);
  [[nodiscard]] const SensorCalibration& calibration() const { return calibration_; }
  [[nodiscard]] const Matrix3& crosstalk() const { return crosstalk_; }
  /// True sensitivity of each channel relative to the calibration sheet's (1 + error).
  [[nodiscard]] const Vector3& sensitivity() const { return sensitivity_; }
  /// N read on each force channel per N m of each moment about the point of origin, within the
  /// nominal moment (this physical sensor's draw).
  [[nodiscard]] const Matrix3& moment_crosstalk() const { return moment_crosstalk_; }
  /// True sensor frame in the flange frame: a turn of misalignment_rad about the tool axis.
  [[nodiscard]] const Matrix3& flange_R_sensor() const { return flange_R_sensor_; }

 private:
  SensorConfig config_;
  ToolConfig tool_;
  Matrix3 crosstalk_;
  Vector3 sensitivity_ = Vector3::Ones();
  Matrix3 response_;  // crosstalk_ times the sensitivities: what a force in the sensor frame reads as
  Matrix3 flange_R_sensor_ = Matrix3::Identity();
  Vector3 zero_drift_n_per_s_ = Vector3::Zero();
  Matrix3 moment_crosstalk_ = Matrix3::Zero();  // N of each force channel per N m of each moment, at nominal
  Vector3 lever_m_ = Vector3::Zero();           // point of origin to the TCP, sensor frame
  SensorCalibration calibration_;
  NoiseEngine rng_;
  boost::random::normal_distribution<double> normal_{0.0, 1.0};
};

/// Standard gravity, m/s^2.
inline constexpr double kGravity = 9.80665;

}  // namespace deflex::cell
