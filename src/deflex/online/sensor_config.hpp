// The force sensor's configuration: calibration (crosstalk), mounting (flange to sensor), payload
// (end-effector mass and centre of gravity), bias, filter and thresholds. Read from YAML.
#pragma once

#include <string>

#include "deflex/model/types.hpp"

namespace deflex {

struct SensorConfig {
  std::string name = "unnamed sensor";
  std::string source = "<defaults>";  ///< file it came from
  int components = 6;                 ///< 3 (forces only) or 6 (forces and moments)

  /// Decoupling matrix applied to the raw reading in the sensor frame: w_decoupled = C w_raw. A 3x3
  /// calibration sheet fills the top-left block (moments pass through unchanged).
  Matrix6 crosstalk = Matrix6::Identity();
  /// Flange to sensor frame (the sensor sits between flange and end effector).
  Pose flange_T_sensor = Pose::Identity();
  double payload_mass_kg = 0.0;                          ///< end effector beyond the sensor
  Vector3 payload_cog_sensor_m = Vector3::Zero();        ///< its centre of gravity, sensor frame
  Vector6 bias_sensor = Vector6::Zero();                 ///< reading at zero load and zero payload, N/Nm
  Vector3 gravity_base_m_s2 = Vector3(0.0, 0.0, -9.81);  ///< gravity in the robot base frame

  double lowpass_cutoff_hz = 25.0;     ///< the paper's value
  int lowpass_order = 2;               ///< 1..8
  double sample_rate_hz = 1000.0;      ///< rate at which samples arrive (the filter is designed for it)
  double dead_band_N = 0.0;            ///< |F| below this counts as zero force
  double dead_band_Nm = 0.0;           ///< |M| below this counts as zero moment
  double fault_threshold_N = 5000.0;   ///< |F| above this is a fault: the sample never moves the robot
  double fault_threshold_Nm = 2000.0;  ///< same for |M|

  /// Throws InputError when a value is out of its domain (non-finite, cut-off above Nyquist ...).
  void validate() const;
};

/// Reads a sensor configuration YAML file (format in docs/online.md). Missing optional fields keep
/// the defaults above. Throws ModelError "FILE:LINE: field 'x': ..." on any bad field.
SensorConfig load_sensor_config(const std::string& yaml_path);

/// load_sensor_config(yaml_path), or for an empty path the defaults above (identity crosstalk, no
/// payload, no bias, the sensor at the flange) with a source that says so: what the command line's
/// --sensor-config gives when it is left out.
SensorConfig load_sensor_config_or_defaults(const std::string& yaml_path);

/// The configuration as YAML in the format load_sensor_config() reads.
std::string sensor_config_to_yaml(const SensorConfig& config);

}  // namespace deflex
