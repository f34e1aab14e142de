// The force-signal conditioning stages of the paper's online strategy (Figure 3), each a small value
// type with one `step`. The frame each stage works in is in its name and comment:
//   sensor frame: crosstalk decoupling, bias removal;
//   sensor -> base: rotation with the current sensor orientation;
//   base frame:  gravity compensation, fault threshold, moment transport to the WAP, low-pass
//                (butterworth_filter.hpp), dead band.
// Wrenches are [F; M] in N and Nm. None of these allocate or throw.
#pragma once

#include "deflex/model/types.hpp"

namespace deflex {

/// Sensor frame: w = C w_raw, C the calibration sheet's decoupling matrix (3x3 into the force block
/// for 3-component sensors).
struct CrosstalkDecoupling {
  Matrix6 matrix = Matrix6::Identity();
  [[nodiscard]] Vector6 step(const Vector6& raw_sensor) const noexcept { return matrix * raw_sensor; }
};

/// Sensor frame: removes the sensor's offset (its reading with nothing mounted and no load).
struct BiasRemoval {
  Vector6 bias_sensor = Vector6::Zero();
  [[nodiscard]] Vector6 step(const Vector6& wrench_sensor) const noexcept { return wrench_sensor - bias_sensor; }
};

/// Sensor frame -> base frame axes: F_base = R F_sensor, M_base = R M_sensor. The moment stays about
/// the sensor origin.
struct RotationToBase {
  [[nodiscard]] static Vector6 step(const Vector6& wrench_sensor, const Matrix3& base_R_sensor) noexcept {
    Vector6 w;
    w.head<3>() = base_R_sensor * wrench_sensor.head<3>();
    w.tail<3>() = base_R_sensor * wrench_sensor.tail<3>();
    return w;
  }
};

/// Base frame: removes the end effector's weight. Gravity m g is a constant in the base frame; its
/// moment about the sensor origin, (R c) x m g, changes with the orientation R (c: centre of gravity
/// in the sensor frame). Input and output: base axes, moment about the sensor origin.
struct GravityCompensation {
  double mass_kg = 0.0;
  Vector3 cog_sensor_m = Vector3::Zero();
  Vector3 gravity_base_m_s2 = Vector3(0.0, 0.0, -9.81);
  [[nodiscard]] Vector6 step(const Vector6& wrench_base_at_sensor, const Matrix3& base_R_sensor) const noexcept {
    const Vector3 weight_base = mass_kg * gravity_base_m_s2;
    Vector6 w = wrench_base_at_sensor;
    w.head<3>() -= weight_base;
    w.tail<3>() -= (base_R_sensor * cog_sensor_m).cross(weight_base);
    return w;
  }
};

/// Base frame: moves the moment from the sensor origin to the wrench application point,
/// M_wap = M_sensor + (p_sensor - p_wap) x F. `wap_sensor_m` is the WAP in the sensor frame.
struct WrenchTransport {
  Vector3 wap_sensor_m = Vector3::Zero();
  [[nodiscard]] Vector6 step(const Vector6& wrench_base_at_sensor, const Matrix3& base_R_sensor) const noexcept {
    const Vector3 sensor_to_wap_base = base_R_sensor * wap_sensor_m;
    Vector6 w = wrench_base_at_sensor;
    w.tail<3>() -= sensor_to_wap_base.cross(w.head<3>());
    return w;
  }
};

/// Base frame: a force (moment) whose magnitude is below the band counts as zero (the paper's lower
/// threshold), so sensor noise at rest does not move the robot.
struct DeadBand {
  double force_N = 0.0;
  double moment_Nm = 0.0;
  /// Returns true when anything was zeroed.
  bool step(Vector6& wrench) const noexcept {
    bool zeroed = false;
    if (wrench.head<3>().norm() < force_N) {
      zeroed = !wrench.head<3>().isZero(0.0);
      wrench.head<3>().setZero();
    }
    if (wrench.tail<3>().norm() < moment_Nm) {
      zeroed = zeroed || !wrench.tail<3>().isZero(0.0);
      wrench.tail<3>().setZero();
    }
    return zeroed;
  }
};

/// The paper's upper threshold: a sample whose force (moment) magnitude exceeds the threshold, or
/// that is not finite, is a fault and must never move the robot.
struct FaultThreshold {
  double force_N = 5000.0;
  double moment_Nm = 2000.0;
  [[nodiscard]] bool is_fault(const Vector6& wrench) const noexcept {
    if (!wrench.allFinite()) {
      return true;
    }
    return wrench.head<3>().norm() > force_N || wrench.tail<3>().norm() > moment_Nm;
  }
};

}  // namespace deflex
