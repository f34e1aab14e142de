// Components of the simulated cell against closed forms: LDBB force direction, first-order response
// and ball friction; lost motion's sign and history; the sensor's compliance; the true robot's fixed
// point against the core's deflected configuration; the force sensor's reading.
#include <gtest/gtest.h>

#include <cmath>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/laser_tracker.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::cell {
namespace {

LdbbConfig quiet_ldbb() {
  LdbbConfig c;
  c.bar_length_m = 0.15;
  c.inclination_rad = deg_to_rad(30.0);
  c.time_constant_s = 0.3;
  c.ripple = 0.0;
  c.noise = 0.0;
  c.seal_friction = 0.0;
  c.seal_friction_spread = 0.0;
  c.ball_friction = 0.0;
  return c;
}

TEST(LdbbDevice, PushesAlongTheBarFromTheTruePivot) {
  LdbbConfig c = quiet_ldbb();
  c.pivot_error_m = Vector3(0.002, -0.001, 0.0);
  LdbbDevice d(c, Vector3(1.8, 0.0, 0.825), 400.0, 1);
  d.settle();
  const Vector3 tcp(1.8 + 0.1299, 0.0, 0.9);
  const Wrench w = d.wrench(tcp, Vector3::Zero());
  const Vector3 bar = tcp - Vector3(1.802, -0.001, 0.825);
  EXPECT_NEAR((w.head<3>() - 400.0 * bar.normalized()).norm(), 0.0, 1e-9);
  EXPECT_TRUE(w.tail<3>().isZero());
  c.push = false;
  LdbbDevice pull(c, Vector3(1.8, 0.0, 0.825), 400.0, 1);
  pull.settle();
  EXPECT_NEAR((pull.wrench(tcp, Vector3::Zero()).head<3>() + 400.0 * bar.normalized()).norm(), 0.0, 1e-9);
}

TEST(LdbbDevice, FirstOrderResponseToTheSetPoint) {
  LdbbConfig c = quiet_ldbb();
  LdbbDevice d(c, Vector3::Zero(), 500.0, 1);
  const double dt = 0.001;
  for (int i = 0; i < 300; ++i) d.advance(dt);  // one time constant
  EXPECT_NEAR(d.magnitude_n(), 500.0 * (1.0 - std::exp(-1.0)), 1e-6);
  for (int i = 0; i < 3000; ++i) d.advance(dt);
  EXPECT_NEAR(d.magnitude_n(), 500.0 * (1.0 - std::exp(-11.0)), 1e-6);
}

TEST(LdbbDevice, TheSealHoldsItsFrictionAgainstThePistonsLastMotion) {
  // A pushing bar along +z from the origin, 400 N, the seal good for 15 % with 0.1 mm of
  // pre-sliding. Extending (the arm yields) the friction builds linearly over the pre-sliding and
  // then takes 15 % off; standing still it holds; retracting 0.1 mm takes it through zero; past
  // 0.2 mm back it adds 15 %. Pulling, the same extension adds to the force.
  LdbbConfig c = quiet_ldbb();
  c.seal_friction = 0.15;
  c.seal_presliding_m = 1e-4;
  LdbbDevice d(c, Vector3::Zero(), 400.0, 1);
  d.settle();
  EXPECT_DOUBLE_EQ(d.seal_friction(), 0.15);
  auto push_at = [&](double length_m) { return d.wrench(Vector3(0, 0, length_m), Vector3::Zero())[2]; };
  EXPECT_NEAR(push_at(0.15), 400.0, 1e-9);           // first contact: nothing held yet
  EXPECT_NEAR(push_at(0.15 + 0.5e-4), 370.0, 1e-6);  // half the pre-sliding: half of 60 N
  EXPECT_NEAR(push_at(0.15 + 3e-4), 340.0, 1e-6);    // sliding out: -15 %
  EXPECT_NEAR(push_at(0.15 + 3e-4), 340.0, 1e-6);    // standing: held
  EXPECT_NEAR(push_at(0.15 + 2e-4), 400.0, 1e-6);    // 0.1 mm back: through zero
  EXPECT_NEAR(push_at(0.15 + 0.5e-4), 460.0, 1e-6);  // sliding in: +15 %
  c.push = false;
  LdbbDevice pull(c, Vector3::Zero(), 400.0, 1);
  pull.settle();
  EXPECT_NEAR(pull.wrench(Vector3(0, 0, 0.15), Vector3::Zero())[2], -400.0, 1e-9);
  EXPECT_NEAR(pull.wrench(Vector3(0, 0, 0.15 + 3e-4), Vector3::Zero())[2], -460.0, 1e-6);
  // Its level differs from run to run around the mean by the spread (here 3 %, 400 runs).
  c.seal_friction_spread = 0.03;
  double sum = 0.0, sum2 = 0.0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    const double mu = LdbbDevice(c, Vector3::Zero(), 400.0, seed).seal_friction();
    sum += mu;
    sum2 += mu * mu;
  }
  const double mean = sum / 400.0;
  EXPECT_NEAR(mean, 0.15, 0.006);
  EXPECT_NEAR(std::sqrt(sum2 / 400.0 - mean * mean), 0.03, 0.005);
}

TEST(LdbbDevice, BallFrictionOpposesTheMotionAcrossTheBar) {
  LdbbConfig c = quiet_ldbb();
  c.ball_friction = 0.1;
  c.ball_radius_m = 0.0127;
  LdbbDevice d(c, Vector3::Zero(), 600.0, 1);
  d.settle();
  const Vector3 tcp(0.0, 0.0, 0.15);  // bar along +z, length 0.15
  const Vector3 v(0.05, 0.0, 0.0);    // moving along +x, across the bar
  const Wrench w = d.wrench(tcp, v);
  EXPECT_NEAR(w[2], 600.0, 1e-9);
  EXPECT_NEAR(w[0], -2.0 * 0.1 * 600.0 * 0.0127 / 0.15, 1e-9);
  EXPECT_NEAR(w[1], 0.0, 1e-12);
}

TEST(LostMotion, FollowsTheSignOfTheTorqueWithHistory) {
  LostMotion lm;
  lm.half_width_rad = 20e-6;
  lm.torque_nm = 100.0;
  EXPECT_DOUBLE_EQ(lm.update(50.0), 0.0);     // below the band: nothing moves
  EXPECT_DOUBLE_EQ(lm.update(150.0), 10e-6);  // half-way across
  EXPECT_DOUBLE_EQ(lm.update(300.0), 20e-6);  // across, saturated
  EXPECT_DOUBLE_EQ(lm.update(0.0), 20e-6);    // unloading keeps the side it was pushed to
  EXPECT_DOUBLE_EQ(lm.update(-100.0), 0.0);   // reversing the torque walks back through the band
  EXPECT_DOUBLE_EQ(lm.update(-250.0), -20e-6);
  EXPECT_DOUBLE_EQ(lm.update(-50.0), -20e-6);
}

TEST(LostMotion, GravityPreloadKeepsAJointOnOneSide) {
  LostMotion lm;
  lm.half_width_rad = 20e-6;
  lm.torque_nm = 300.0;
  const double gravity = 9000.0;
  EXPECT_DOUBLE_EQ(lm.update(gravity), 20e-6);
  for (double process : {1200.0, -1200.0, 500.0, -2000.0}) {
    EXPECT_DOUBLE_EQ(lm.update(gravity + process), 20e-6) << process;  // never crosses its band
  }
}

// The built-in robot with nothing but its lumped joint stiffness (scale 1, no spread, no extra effect).
CellConfig bare_cell() {
  CellConfig c;
  c.robot.gravity_torque_nm = {0, 9000, 3500, 0, 60, 0};
  return c;
}

JointVector test_pose() {
  JointVector q(6);
  q << 0.1, deg_to_rad(25.0), deg_to_rad(5.0), 0.2, deg_to_rad(55.0), -0.3;
  return q;
}

TEST(TrueRobot, LumpedOnlyMatchesTheCoresDeflectedConfiguration) {
  const CellConfig c = bare_cell();
  const TrueRobot robot(c, false, 7);
  Workspace ws(robot.true_model());
  const JointVector q = test_pose();
  Wrench w;
  w << 300.0, -200.0, 500.0, 0.0, 0.0, 0.0;
  TrueRobotState s = robot.initial_state(q);
  const Vector3 p = robot.solve(ws, q, w, s);
  JointVector q_actual;
  ASSERT_EQ(deflected_configuration(robot.true_model(), ws, q, w, q_actual), DeflectionStatus::kConverged);
  // Within a nanometre (the cell stops its fixed point at 1e-10 rad: 0.3 nm at the TCP).
  EXPECT_NEAR((p - tcp_pose(robot.true_model(), ws, q_actual).translation()).norm(), 0.0, 1e-9);
  // And the true stiffness is the built-in one when scale 1 and spread 0.
  for (int j = 0; j < 6; ++j) {
    EXPECT_DOUBLE_EQ(robot.true_model().stiffness()[j], robot.nominal_model().stiffness()[j]);
  }
}

TEST(TrueRobot, SensorComplianceAddsTheCantileverDeflection) {
  CellConfig c = bare_cell();
  c.sensor.lateral_compliance_m_per_n = 0.5e-6;
  c.sensor.rotational_compliance_rad_per_nm = 4e-6;
  c.sensor.axial_compliance_m_per_n = 0.0;
  const TrueRobot robot(c, true, 7);
  Workspace ws(robot.true_model());
  forward_kinematics(robot.true_model(), ws, test_pose());
  // A force along the flange x axis at the TCP, which sits ee_length beyond the sensor origin along
  // flange z: the sensor shears by c_lat F and tilts by c_rot F L, which moves the TCP by c_rot F L^2.
  const Vector3 x_flange = ws.base_T_flange.linear().col(0);
  Wrench w;
  w << 200.0 * x_flange, Vector3::Zero();
  const double L = c.tool.ee_length_m;
  const Vector3 d = robot.structural_displacement(ws, w);
  EXPECT_NEAR((d - x_flange * 200.0 * (0.5e-6 + 4e-6 * L * L)).norm(), 0.0, 1e-12);
  // Without the sensor mounted, nothing is added.
  const TrueRobot bare(c, false, 7);
  Workspace ws2(bare.true_model());
  forward_kinematics(bare.true_model(), ws2, test_pose());
  EXPECT_NEAR(bare.structural_displacement(ws2, w).norm(), 0.0, 1e-15);
}

TEST(ForceSensorDaq, MeasuresProcessForceAndWeightInTheSensorFrame) {
  SensorConfig s;
  s.crosstalk = 0.0;
  s.noise_n = 0.0;
  s.bias_n = Vector3(1.0, 2.0, 3.0);
  ToolConfig tool;
  tool.ee_mass_kg = 5.0;
  ForceSensorDaq daq(s, tool, 3);
  const Matrix3 R = Eigen::AngleAxisd(kPi, Vector3::UnitY()).toRotationMatrix();  // tool pointing down
  const Vector3 f = daq.sample(Vector3(10.0, 0.0, 100.0), R);
  // In the flipped frame x and z change sign; the weight (-z in the base) reads +z in the sensor.
  EXPECT_NEAR(f.x(), -10.0 + 1.0, 1e-12);
  EXPECT_NEAR(f.y(), 0.0 + 2.0, 1e-12);
  EXPECT_NEAR(f.z(), -100.0 + 5.0 * kGravity + 3.0, 1e-12);
}

TEST(ForceSensorDaq, DecouplingUndoesTheCrosstalkUpToTheCalibrationResidual) {
  SensorConfig s;
  s.crosstalk = 0.02;
  s.crosstalk_calibration_residual = 0.0;
  s.noise_n = 0.0;
  ForceSensorDaq daq(s, ToolConfig{}, 5);
  EXPECT_GT((daq.crosstalk() - Matrix3::Identity()).norm(), 1e-3);
  const Vector3 raw = daq.sample(Vector3(100.0, -50.0, 20.0), Matrix3::Identity());
  EXPECT_NEAR((daq.calibration().decoupling * raw - Vector3(100.0, -50.0, 20.0)).norm(), 0.0, 1e-9);
}

TEST(ForceSensorDaq, ForceChannelsAnswerToTheMomentAboutTheSensorsOrigin) {
  // A lateral force at the TCP, 250 mm beyond a 60 mm sensor, bends the sensor about its centre
  // with M = 0.28 m x F. The force channels read the force plus the unit's moment crosstalk times
  // M (at most 1 % of 1 kN per 50 N m: 0.2 N per N m); beyond 50 N m the response grows by 50 % per
  // nominal moment over it.
  SensorConfig s;
  s.crosstalk = 0.0;
  s.noise_n = 0.0;
  s.height_m = 0.06;
  s.moment_crosstalk = 0.01;
  s.nominal_moment_nm = 50.0;
  s.nominal_lateral_force_n = 1000.0;
  s.moment_overload_growth = 0.5;
  ToolConfig tool;
  tool.ee_length_m = 0.25;
  ForceSensorDaq daq(s, tool, 3, 11);
  const Matrix3& X = daq.moment_crosstalk();
  EXPECT_GT(X.cwiseAbs().maxCoeff(), 0.01);
  EXPECT_LE(X.cwiseAbs().maxCoeff(), 0.2);
  // 100 N along x: My = 0.28 * 100 = 28 N m, inside the nominal.
  const Vector3 small = daq.sample(Vector3(100.0, 0.0, 0.0), Matrix3::Identity());
  EXPECT_NEAR((small - Vector3(100.0, 0.0, 0.0) - X.col(1) * 28.0).norm(), 0.0, 1e-9);
  // 300 N: My = 84 N m, 0.68 nominal moments over: the response is 84 x 1.34.
  const Vector3 large = daq.sample(Vector3(300.0, 0.0, 0.0), Matrix3::Identity());
  EXPECT_NEAR((large - Vector3(300.0, 0.0, 0.0) - X.col(1) * 84.0 * 1.34).norm(), 0.0, 1e-9);
  // An axial force has no lever: nothing.
  const Vector3 axial = daq.sample(Vector3(0.0, 0.0, 500.0), Matrix3::Identity());
  EXPECT_NEAR((axial - Vector3(0.0, 0.0, 500.0)).norm(), 0.0, 1e-9);
  // The same physical sensor (unit seed) has the same crosstalk in every run.
  EXPECT_TRUE(ForceSensorDaq(s, tool, 99, 11).moment_crosstalk().isApprox(X));
}

TEST(LaserTracker, StampsOnItsOwnClockStartedByAJitteryTrigger) {
  // A tracker whose trigger lands 1 ms late or early (1 sigma) and whose clock runs 50 ppm fast or
  // slow (1 sigma). The reflector moves along x at 1 m per simulated second, so each sample's x is
  // the simulated time it was taken at. Its stamps step by exactly its own 1 ms; stamp against x
  // gives its rate (1 + r) and, at the first sample, its trigger offset.
  TrackerConfig c;
  c.noise_m = 0.0;
  c.rate_hz = 1000.0;
  c.trigger_jitter_s = 1e-3;
  c.clock_rate_error = 50e-6;
  double sum_d = 0.0, sum_d2 = 0.0, sum_r = 0.0, sum_r2 = 0.0;
  const int runs = 300;
  for (int seed = 1; seed <= runs; ++seed) {
    LaserTracker tracker(c, static_cast<std::uint64_t>(seed), 1.0, 21.0, 1.0);
    TrackerTrace trace;
    for (int k = 0; k < 5500; ++k) {
      const double t0 = k * 0.004, t1 = (k + 1) * 0.004;
      tracker.observe(t0, Vector3(t0, 0.0, 0.0), t1, Vector3(t1, 0.0, 0.0), trace);
    }
    ASSERT_GT(trace.size(), 19900u);
    for (std::size_t i = 1; i < trace.size(); ++i) {
      ASSERT_NEAR(trace[i].t_s - trace[i - 1].t_s, 1e-3, 1e-9);
    }
    const double rate = (trace.back().t_s - trace.front().t_s) / (trace.back().p_m.x() - trace.front().p_m.x());
    const double trigger = trace.front().p_m.x() - 1.0 - trace.front().t_s / rate;
    sum_r += rate - 1.0;
    sum_r2 += (rate - 1.0) * (rate - 1.0);
    sum_d += trigger;
    sum_d2 += trigger * trigger;
  }
  const double mean_d = sum_d / runs, mean_r = sum_r / runs;
  EXPECT_NEAR(mean_d, 0.0, 2.5e-4);
  EXPECT_NEAR(std::sqrt(sum_d2 / runs - mean_d * mean_d), 1e-3, 1.5e-4);
  EXPECT_NEAR(mean_r, 0.0, 12e-6);
  EXPECT_NEAR(std::sqrt(sum_r2 / runs - mean_r * mean_r), 50e-6, 7.5e-6);
}

}  // namespace
}  // namespace deflex::cell
