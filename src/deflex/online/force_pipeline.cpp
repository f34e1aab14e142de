// The conditioning chain (see force_pipeline.hpp).
#include "deflex/online/force_pipeline.hpp"

#include <cmath>

namespace deflex {

ForcePipeline::ForcePipeline(const SensorConfig& config, const Pose& sensor_T_wap) : config_(config) {
  config_.validate();
  crosstalk.matrix = config_.crosstalk;
  bias.bias_sensor = config_.bias_sensor;
  gravity.mass_kg = config_.payload_mass_kg;
  gravity.cog_sensor_m = config_.payload_cog_sensor_m;
  gravity.gravity_base_m_s2 = config_.gravity_base_m_s2;
  fault.force_N = config_.fault_threshold_N;
  fault.moment_Nm = config_.fault_threshold_Nm;
  transport.wap_sensor_m = sensor_T_wap.translation();
  lowpass = ButterworthLowPass(
      design_butterworth_lowpass(config_.lowpass_order, config_.lowpass_cutoff_hz, config_.sample_rate_hz));
  dead_band.force_N = config_.dead_band_N;
  dead_band.moment_Nm = config_.dead_band_Nm;
}

ConditionedWrench ForcePipeline::step(const ForceSample& raw, const Matrix3& base_R_sensor) noexcept {
  ConditionedWrench out;
  if (!raw.valid || !raw.wrench_sensor.allFinite() || !std::isfinite(raw.t_s) || !base_R_sensor.allFinite()) {
    out.wrench_base = last_.wrench_base;
    out.status = PipelineStatus::kInvalidSample;
    return out;
  }
  Vector6 w = crosstalk.step(raw.wrench_sensor);
  if (config_.components == 3) {
    w.tail<3>().setZero();  // a 3-component sensor has no moment channels, whatever the matrix says
  }
  w = bias.step(w);
  w = RotationToBase::step(w, base_R_sensor);
  w = gravity.step(w, base_R_sensor);
  if (config_.components == 3) {
    // A 3-component sensor cannot see moments: the force is taken to act at the WAP (the paper's
    // point force at the TCP), so the moment about the WAP is zero and there is nothing to transport.
    w.tail<3>().setZero();
  }
  if (fault.is_fault(w)) {
    out.wrench_base = last_.wrench_base;
    out.status = PipelineStatus::kFault;
    return out;
  }
  if (config_.components == 6) {
    w = transport.step(w, base_R_sensor);
  }
  w = lowpass.step(w);
  out.status = dead_band.step(w) ? PipelineStatus::kDeadBand : PipelineStatus::kOk;
  out.wrench_base = w;
  last_ = out;
  return out;
}

void ForcePipeline::reset() noexcept {
  lowpass = ButterworthLowPass(lowpass.design());
  last_ = ConditionedWrench{};
}

}  // namespace deflex
