// The whole conditioning chain: raw sensor sample + current sensor orientation -> the process wrench
// at the wrench application point (WAP), in the robot base frame, ready for the compliance model.
#pragma once

#include "deflex/online/butterworth_filter.hpp"
#include "deflex/online/conditioning_stages.hpp"
#include "deflex/online/force_sample.hpp"
#include "deflex/online/sensor_config.hpp"

namespace deflex {

/// Sign convention of KDL and deflex: >= 0 usable, < 0 the sample was rejected.
enum class PipelineStatus : int {
  kOk = 0,
  kDeadBand = 1,        ///< usable; part of the wrench was inside the dead band and set to zero
  kFault = -1,          ///< above the fault threshold: rejected, filter state untouched
  kInvalidSample = -2,  ///< non-finite or flagged invalid by the source: rejected
};

struct ConditionedWrench {
  Wrench wrench_base = Wrench::Zero();  ///< base frame, moment about the WAP, filtered
  PipelineStatus status = PipelineStatus::kOk;
};

/// Stage order (docs/online.md explains the frames): crosstalk, bias (sensor frame); rotation to
/// base; gravity; fault check on the unfiltered compensated wrench; transport to the WAP; low-pass;
/// dead band. The paper filters before subtracting gravity; since the filter is linear with unit DC
/// gain the two orders agree at a fixed orientation, and subtracting gravity first stays exact while
/// the orientation changes.
/// Thread safety: one thread at a time (the filter's state).
class ForcePipeline {
 public:
  /// `sensor_T_wap`: the WAP in the sensor frame (flange_T_sensor^-1 flange_T_wap). Throws InputError
  /// on an invalid configuration.
  explicit ForcePipeline(const SensorConfig& config, const Pose& sensor_T_wap = Pose::Identity());

  /// Conditions one sample taken at sensor orientation base_R_sensor. Never allocates or throws.
  ConditionedWrench step(const ForceSample& raw, const Matrix3& base_R_sensor) noexcept;
  /// Forgets the filter state (the next sample primes it).
  void reset() noexcept;

  [[nodiscard]] const SensorConfig& config() const { return config_; }
  [[nodiscard]] const ConditionedWrench& last() const { return last_; }

  CrosstalkDecoupling crosstalk;
  BiasRemoval bias;
  GravityCompensation gravity;
  FaultThreshold fault;
  WrenchTransport transport;
  ButterworthLowPass lowpass;
  DeadBand dead_band;

 private:
  SensorConfig config_;
  ConditionedWrench last_;
};

}  // namespace deflex
