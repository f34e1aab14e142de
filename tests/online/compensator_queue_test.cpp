// The compensator's sample queue at the paper's slow cycle: a 1 kHz DAQ delivers 100 samples per
// 100 ms cycle, and every one of them must reach the low-pass filter (none dropped), without any
// allocation in the cycle.
#include <gtest/gtest.h>

#include "deflex/online/online_compensator.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

TEST(CompensatorQueue, EverySampleOfASlowCycleReachesTheFilter) {
  const RobotModel robot = builtin_irb6700();
  SensorConfig sensor;
  sensor.components = 3;
  sensor.sample_rate_hz = 1000.0;
  sensor.lowpass_cutoff_hz = 25.0;
  sensor.fault_threshold_N = 3000.0;
  OnlineConfig config;
  config.period_s = 0.1;  // the paper's cycle
  OnlineCompensator comp(robot, sensor, config);
  CycleInput in;
  in.q_planned = JointVector::Zero(6);
  in.q_planned << 0, 0.5, 0.2, 0, 0.8, 0;
  in.q_feedback = in.q_planned;
  ForceSample s;
  s.wrench_sensor = Wrench::Zero();
  s.wrench_sensor[2] = 200.0;
  double t = 0.0;
  test::AllocationGuard guard;
  for (int cycle = 0; cycle < 5; ++cycle) {
    for (int k = 0; k < 100; ++k) {  // 100 ms of 1 kHz samples between two cycles
      t += 1e-3;
      s.t_s = t;
      comp.push_force(s);
    }
    in.t_s = t;
    const CycleOutput out = comp.step(in);
    EXPECT_EQ(out.samples_used, 100) << "cycle " << cycle;
  }
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_EQ(comp.counters().samples_dropped, 0u);
  EXPECT_EQ(comp.counters().samples_ok, 500u);
}

}  // namespace
}  // namespace deflex
