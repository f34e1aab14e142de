// One force/torque sample as the sensor gives it, and the interface every force input implements
// (UDP stream, CSV replay, the simulated cell's sensor), so the compensator does not care which.
#pragma once

#include <cstdint>

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

/// What a force source counts, for the session's status and summary; each source fills what applies
/// to it (a CSV replay has no sequence numbers).
struct ForceSourceStats {
  std::uint64_t received = 0;      ///< samples (records) read from the wire or the file
  std::uint64_t accepted = 0;      ///< samples handed on
  std::uint64_t malformed = 0;     ///< datagrams of the wrong size, header or layout
  std::uint64_t out_of_order = 0;  ///< samples older than one already handed on (dropped)
  std::uint64_t duplicates = 0;    ///< samples seen before (dropped)
  std::uint64_t lost = 0;          ///< samples the sequence numbers say were sent but never arrived
  std::uint64_t faulty = 0;        ///< samples the sensor itself flagged (status bits, saturation): handed on invalid
  std::uint64_t restarts = 0;      ///< the sender's sequence restarted, or the stream was requested again
  std::uint64_t re_requests = 0;   ///< of those, the stream requested again because it stopped or never came
  std::uint64_t saturated = 0;     ///< of the faulty ones, those at the sensor's range limits
  std::uint32_t last_status = 0;   ///< the last non-zero status word the sensor sent (0: none)
};

/// A source of force samples. `latest` is non-blocking and never allocates: it returns true with a
/// sample not returned before (oldest first; a source that fell behind may skip samples) and false
/// when there is nothing new. The compensator calls it until it returns false, once per cycle, so
/// that every sample passes through the low-pass filter designed for the sensor's sample rate.
/// Thread safety: one thread at a time (the loop's) for every source but ForceHandoff, whose push()
/// is for a driver's own thread.
class ForceSource {
 public:
  virtual ~ForceSource() = default;
  virtual bool latest(ForceSample& out) noexcept = 0;
  /// Its counts so far (read between cycles, on the loop's thread). Never allocates.
  [[nodiscard]] virtual ForceSourceStats stats() const noexcept { return {}; }
};

}  // namespace deflex
