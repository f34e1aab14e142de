// Time alignment: a known clock offset (and drift) recovered from a path measured with noise and a
// deflection, against the commanded path on its own clock; and bad input refused.
#include "deflex/evaluate/time_alignment.hpp"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// A commanded path with a start, a stop and changes of speed: a circle of 100 mm at up to 50 mm/s with
// a hold before and after, sampled at 250 Hz on the program's clock.
Vector3 command_at(double t) {
  const double s = std::clamp(t - 1.0, 0.0, 20.0);                                       // 1 s hold, 20 s motion
  const double phase = 2 * kPi * (s / 20.0 - std::sin(2 * kPi * s / 20.0) / (2 * kPi));  // smooth start and stop
  return {1.9 + 0.1 * std::cos(3 * phase), 0.1 * std::sin(3 * phase), 0.9};
}

TrackerTrace circle_command() {
  TrackerTrace c;
  for (int i = 0; i <= 23 * 250; ++i) c.push_back({i / 250.0, command_at(i / 250.0)});
  return c;
}

// The tracker at 1 kHz on its own clock: program time = tracker time + offset + drift (t - t0).
TrackerTrace tracker_run(double offset, double drift, double t0, double noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  TrackerTrace m;
  for (int i = 0; i < 20000; ++i) {
    const double t_tracker = 5000.0 + i * 1e-3;
    const double t_program = t_tracker + offset + drift * (t_tracker - t0);
    // A deflection of 0.5 mm that follows the direction of the path (as a push normal to a circle does).
    const Vector3 p = command_at(t_program);
    const Vector3 d = (p - Vector3(1.9, 0.0, 0.9)).normalized() * 0.5e-3 + Vector3(0, 0, -0.2e-3);
    m.push_back({t_tracker, p + d + Vector3(n(rng), n(rng), n(rng))});
  }
  return m;
}

TEST(TimeAlignment, RecoversAKnownOffsetToWellUnderOneSample) {
  const double offset = -4998.2345;  // tracker 5000 s = program 1.7655 s
  const TimeAlignment a = align_time(tracker_run(offset, 0.0, 0.0, 10e-6, 1), circle_command());
  EXPECT_NEAR(a.offset_s, offset, 1e-4);  // a tracker sample is 1e-3 s
  EXPECT_TRUE(std::isfinite(a.offset_std_s));
  EXPECT_LT(a.offset_std_s, 1e-3);
  EXPECT_NEAR(a.rms_m, std::sqrt(0.5e-3 * 0.5e-3 + 0.2e-3 * 0.2e-3), 0.05e-3);  // the deflection, seen in time
  EXPECT_GT(a.moving_fraction, 0.8);
}

TEST(TimeAlignment, FitsADriftOf50PpmWhenAsked) {
  const double offset = -4998.5, drift = 50e-6, t0 = 5010.0;
  TimeAlignmentOptions o;
  o.fit_drift = true;
  const TrackerTrace m = tracker_run(offset, drift, t0, 10e-6, 2);
  const TimeAlignment a = align_time(m, circle_command(), o);
  EXPECT_NEAR(a.drift, drift, 5e-6);
  // Compare the mapping, not the parameters (the fit takes its drift about the run's middle).
  for (double t : {5001.0, 5010.0, 5019.0}) EXPECT_NEAR(a.program_time(t), t + offset + drift * (t - t0), 2e-4);
  // Without the drift the offset is the mean one and the residual is larger.
  const TimeAlignment plain = align_time(m, circle_command());
  EXPECT_GT(plain.rms_m, a.rms_m);
}

TEST(TimeAlignment, SearchRangeAndBadInput) {
  const TrackerTrace m = tracker_run(-4998.2345, 0.0, 0.0, 10e-6, 3);
  TimeAlignmentOptions o;
  o.centre_s = -4998.0;
  o.search_s = 0.5;
  EXPECT_NEAR(align_time(m, circle_command(), o).offset_s, -4998.2345, 1e-4);
  o.centre_s = 0.0;  // nowhere near: no overlap
  EXPECT_THROW(align_time(m, circle_command(), o), InputError);
  TrackerTrace still = circle_command();
  for (auto& s : still) s.p_m = Vector3(1, 2, 3);
  EXPECT_THROW(align_time(m, still, {}), InputError);
  TrackerTrace back = m;
  std::swap(back[10].t_s, back[11].t_s);
  EXPECT_THROW(align_time(back, circle_command(), {}), InputError);
  EXPECT_THROW(align_time(TrackerTrace(m.begin(), m.begin() + 5), circle_command(), {}), InputError);
}

}  // namespace
}  // namespace deflex
