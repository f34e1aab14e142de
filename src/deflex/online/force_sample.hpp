// One force/torque sample as the sensor gives it, and the interface every force input implements
// (UDP stream, CSV replay, the simulated cell's sensor), so the compensator does not care which.
#pragma once

#include "deflex/model/types.hpp"

namespace deflex {

/// A raw sensor reading: wrench [Fx Fy Fz Mx My Mz] in N and Nm, in the SENSOR frame, moment about
/// the sensor origin, taken as the wrench the environment and the end effector exert on the sensor's
/// tool side (the sign the robot model expects for a process force). 3-component sensors leave the
/// moments at 0. `t_s` is the sensor's own time stamp (s); the compensator never compares it with
/// the controller's clock (the watchdog uses arrival times).
struct ForceSample {
  double t_s = 0.0;
  Vector6 wrench_sensor = Vector6::Zero();
  bool valid = true;  ///< false: the source knows this sample is bad (DAQ overrun, saturation)
};

/// A source of force samples. `latest` is non-blocking and never allocates: it returns true with a
/// sample not returned before (oldest first; a source that fell behind may skip samples) and false
/// when there is nothing new. The compensator calls it until it returns false, once per cycle, so
/// that every sample passes through the low-pass filter designed for the sensor's sample rate.
class ForceSource {
 public:
  virtual ~ForceSource() = default;
  virtual bool latest(ForceSample& out) noexcept = 0;
};

}  // namespace deflex
