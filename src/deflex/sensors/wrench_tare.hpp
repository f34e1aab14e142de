// The software tare of a force source (`--tare`): with the arm held still at start, the mean reading
// over a stated window becomes an offset subtracted from every later sample, in the sensor frame.
// The window's standard deviation on each axis shows whether the arm really stood still (motion,
// vibration, a tool still running): above the stated limit the tare is refused rather than baking a
// moving force into every later sample. A faulty sample in the window refuses it too.
//
// The tare is deflex's own and is kept apart from the sensor's bias command (RDT 0x0042), which
// changes the sensor's zero for every program reading it and outlives deflex. How it meets the payload
// identification (docs/online.md, "Payload identification"): the identification's `bias` is the
// reading with no load and no payload; a tare taken with the payload mounted also holds the payload's
// weight at the tare pose. Give that weight as `expected_wrench_sensor` (payload_wrench_sensor()) and
// the tare removes only the sensor's offset, so the gravity compensation stays right at every pose;
// leave it zero and the tare removes the weight at the tare pose only (right for a configuration with
// no payload, and for tasks that keep the tool's orientation). Either way the sensor configuration's
// `bias` must then be zero, or the offset is removed twice.
#pragma once

#include <string>

#include "deflex/model/types.hpp"
#include "deflex/online/force_sample.hpp"

namespace deflex {

struct TareSettings {
  double window_s = 0.5;            ///< how long the arm is held still (s)
  double max_std_force_n = 0.5;     ///< largest standard deviation of any force axis over the window (N)
  double max_std_torque_nm = 0.05;  ///< same for the torque axes (Nm)
  /// What the sensor should read at the tare pose with no process force (N, Nm, sensor frame): the
  /// payload's weight there. Zero: the tare takes out everything it reads.
  Vector6 expected_wrench_sensor = Vector6::Zero();
  /// Throws InputError naming the field when a value is out of its domain.
  void validate() const;
};

enum class TareState {
  kOff,         ///< no tare asked for: samples pass unchanged
  kCollecting,  ///< averaging the window: samples are taken in, none handed on
  kDone,        ///< the offset is subtracted from every sample
  kRejected,    ///< the window moved too much or held a faulty sample: nothing is handed on
};
[[nodiscard]] const char* to_string(TareState s);

struct TareResult {
  TareState state = TareState::kOff;
  int samples = 0;                          ///< samples averaged so far
  int samples_wanted = 0;                   ///< window x rate
  int faulty = 0;                           ///< invalid samples seen in the window (any: rejected)
  Vector6 mean_sensor = Vector6::Zero();    ///< N, Nm
  Vector6 std_sensor = Vector6::Zero();     ///< standard deviation per axis, N, Nm
  Vector6 offset_sensor = Vector6::Zero();  ///< mean - expected: subtracted from every sample
};

/// "tare done: 500 samples over 0.5 s, offset [..] N/Nm, std <= 0.12 N, 0.004 Nm" or why refused.
[[nodiscard]] std::string describe(const TareResult& result, const TareSettings& settings);

/// The payload's weight as the sensor reads it (N, Nm, sensor frame, moment about the sensor origin):
/// force m sensor_R_base g, moment c x that force (c: centre of gravity, sensor frame). The inverse of
/// the pipeline's gravity compensation, for `TareSettings::expected_wrench_sensor`.
[[nodiscard]] Vector6 payload_wrench_sensor(double mass_kg, const Vector3& cog_sensor_m,
                                            const Vector3& gravity_base_m_s2, const Matrix3& base_R_sensor);

/// The tare's state machine and running statistics (Welford's, so a long window stays exact).
/// Never allocates; add() and apply() never throw.
/// Thread safety: one thread at a time.
class WrenchTare {
 public:
  /// Starts a new window of `settings.window_s` at `rate_hz` samples a second. Throws InputError.
  void start(const TareSettings& settings, double rate_hz);
  /// Forgets the tare: samples pass unchanged.
  void clear() noexcept { result_ = TareResult{}; }
  /// Takes one sample while collecting; returns the state after it.
  TareState add(const ForceSample& sample) noexcept;
  /// The sample's wrench less the offset (kDone), or unchanged (kOff).
  [[nodiscard]] Vector6 apply(const Vector6& wrench_sensor) const noexcept {
    return result_.state == TareState::kDone ? Vector6(wrench_sensor - result_.offset_sensor) : wrench_sensor;
  }
  [[nodiscard]] const TareResult& result() const { return result_; }
  [[nodiscard]] const TareSettings& settings() const { return settings_; }

 private:
  void finish() noexcept;
  TareSettings settings_;
  TareResult result_;
  Vector6 m2_ = Vector6::Zero();  // Welford's sum of squared deviations
};

}  // namespace deflex
