// The laser tracker (Leica AT901-class with a 0.5" reflector on the TCP): samples the true TCP at
// its own rate with its noise, between the servo ticks of the simulation (the TCP interpolated
// linearly within a tick). Time stamps are the tracker's own clock's: it is started by the program's
// trigger at a chosen origin (the start of the laps), late or early by the trigger's jitter, and runs
// fast or slow by its rate error.
#pragma once

#include <cstdint>
#include <random>

#include <boost/random/normal_distribution.hpp>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/noise_engine.hpp"
#include "deflex/model/tracker_trace.hpp"

namespace deflex::cell {

/// Thread safety: one thread at a time (observe() draws from its own random generator).
class LaserTracker {
 public:
  /// Samples from `first_sample_s` on (simulation time), stamped relative to `time_origin_s`, until
  /// `last_sample_s`.
  LaserTracker(const TrackerConfig& config, std::uint64_t seed, double first_sample_s, double last_sample_s,
               double time_origin_s);

  /// The TCP moved from p0 at t0 to p1 at t1 (a servo tick): records every sample due in (t0, t1].
  void observe(double t0_s, const Vector3& p0_m, double t1_s, const Vector3& p1_m, TrackerTrace& out);

 private:
  TrackerConfig config_;
  NoiseEngine rng_;
  boost::random::normal_distribution<double> normal_{0.0, 1.0};
  double next_s_, last_s_, origin_s_, period_s_;
  double trigger_s_ = 0.0;  // when its clock read zero, relative to the origin (simulation time)
  double rate_ = 1.0;       // its clock's seconds per simulated second
};

}  // namespace deflex::cell
