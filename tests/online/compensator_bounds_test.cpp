// The TCP bound holds on every cycle of a rate-limited ramp, not only once the target is reached:
// a case (found by a random search) where joint-by-joint rate clamping left the direction of the
// correction and passed the bound on the way.
#include <gtest/gtest.h>

#include "deflex/online/online_compensator.hpp"
#include "deflex/robotfile/robot_io.hpp"

namespace deflex {
namespace {

struct Ramp {
  double max_tcp_m = 0.0;    // largest |J_p dtheta| over the ramp
  double final_tcp_m = 0.0;  // at the end
};

Ramp ramp(double max_tcp_correction_m) {
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0.0, 0.0, 0.3);
  const RobotModel robot = builtin_irb6700().with_tool(tool);
  SensorConfig sensor;  // at the flange
  sensor.components = 6;
  sensor.sample_rate_hz = 250.0;
  sensor.fault_threshold_N = 1e5;
  sensor.fault_threshold_Nm = 1e5;
  OnlineConfig cfg;
  cfg.period_s = 0.004;
  cfg.max_joint_correction_rad = 1.0;  // only the TCP bound acts
  cfg.max_tcp_correction_m = max_tcp_correction_m;
  cfg.max_correction_rate_rad_s = 0.02;
  cfg.watchdog_s = 100.0;
  OnlineCompensator comp(robot, sensor, cfg);
  JointVector q(6);
  q << -0.105, 0.538, -0.384, -0.691, 0.496, -0.216;
  ForceSample s;
  s.wrench_sensor << -38.7, 287.1, 458.6, 16.8, -120.1, -543.2;
  Ramp r;
  CycleOutput out;
  for (int k = 0; k < 3000; ++k) {
    s.t_s = 0.004 * k;
    comp.push_force(s);
    out = comp.step({0.004 * k, q, q});
    r.max_tcp_m = std::max(r.max_tcp_m, out.tcp_correction_m);
  }
  r.final_tcp_m = out.tcp_correction_m;
  return r;
}

TEST(CompensatorBounds, TcpBoundHoldsThroughoutTheRateLimitedRamp) {
  const Ramp free = ramp(1.0);  // the bound far away: the model's own correction
  ASSERT_GT(free.final_tcp_m, 1e-3);
  const double bound = 0.995 * free.final_tcp_m;  // now the bound cuts the target a little
  const Ramp bounded = ramp(bound);
  EXPECT_NEAR(bounded.final_tcp_m, bound, 1e-12);
  EXPECT_LE(bounded.max_tcp_m, bound * (1.0 + 1e-12)) << "the ramp passed the TCP bound on its way";
  // Without the bound, the ramp never goes beyond where it ends either (it moves along a line).
  EXPECT_LE(free.max_tcp_m, free.final_tcp_m * (1.0 + 1e-12));
}

}  // namespace
}  // namespace deflex
