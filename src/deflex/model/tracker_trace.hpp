// Laser-tracker traces: time-stamped TCP positions (their CSV form: evaluate/tracker_csv.hpp).
#pragma once

#include <vector>

#include "deflex/model/types.hpp"

namespace deflex {

/// One tracker reading: time (s) and the measured TCP (reflector) position (m), in the robot base
/// frame or in the tracker's own frame; every trace compared with another must use the same frame.
struct TrackerSample {
  double t_s = 0.0;
  Vector3 p_m = Vector3::Zero();
};

/// A measured (or simulated) path: samples in time order.
using TrackerTrace = std::vector<TrackerSample>;

/// Total length of the polyline through the samples (m).
double trace_length_m(const TrackerTrace& trace);

}  // namespace deflex
