// The cell's realism effects against closed forms: the hardening gear curve (integral of its tangent
// compliance, and the true robot's fixed point with it), the run-to-run drift's statistics, and the
// force sensor's unknown sensitivity error and mounting misalignment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/model/detail/kinematics_count.hpp"
#include "deflex/model/kinematics.hpp"

namespace deflex::cell {
namespace {

// Deflection (in linear-gear torque units) from zero torque to x, by integrating the tangent
// compliance 1 + s exp(-|t|/th) with the midpoint rule: independent of the closed form in the code.
double integrated_curve(double s, double th, double x) {
  const int n = 20000;
  double sum = 0.0;
  const double h = x / n;
  for (int i = 0; i < n; ++i) {
    const double t = (i + 0.5) * h;
    sum += (1.0 + s * std::exp(-std::abs(t) / th)) * h;
  }
  return sum;
}

TEST(GearHardening, DeflectionIsTheIntegralOfTheTangentCompliance) {
  GearHardening g{0.6, 800.0};
  for (double x : {-3000.0, -150.0, 0.0, 40.0, 400.0, 1300.0, 8000.0}) {
    EXPECT_NEAR(g.equivalent_torque(x), integrated_curve(0.6, 800.0, x), 1e-6 * (1.0 + std::abs(x))) << x;
  }
  // Secant stiffness: softer at small torque than at large (a linear stiffness identified at one
  // load misestimates the others). At 100 Nm the gear is ~1.56x softer, at 5000 Nm ~1.1x.
  EXPECT_NEAR(g.equivalent_torque(100.0) / 100.0, 1.0 + 0.6 * 8.0 * (1.0 - std::exp(-0.125)), 1e-12);
  EXPECT_GT(g.equivalent_torque(100.0) / 100.0, 1.5);
  EXPECT_LT(g.equivalent_torque(5000.0) / 5000.0, 1.1);
  // On a large preload (gravity) the increment is nearly linear; on none it is not.
  EXPECT_NEAR(g.increment(20000.0, 500.0) / 500.0, 1.0, 1e-9);
  EXPECT_NEAR(g.increment(0.0, 500.0), integrated_curve(0.6, 800.0, 500.0), 1e-6);
  EXPECT_NEAR(g.increment(300.0, -200.0), integrated_curve(0.6, 800.0, 100.0) - integrated_curve(0.6, 800.0, 300.0),
              1e-6);
  EXPECT_EQ(GearHardening{}.equivalent_torque(123.0), 123.0);
}

CellConfig hardening_case() {
  CellConfig c;
  c.robot.gravity_torque_nm = {0, 9000, 3500, 0, 60, 0};  // the paper case's preload
  c.robot.hardening_softening = {0.6, 0.6, 0.6, 0.6, 0.6, 0.6};
  c.robot.hardening_torque_nm = {800, 1500, 1000, 120, 120, 60};
  return c;
}

TEST(TrueRobot, HardeningGearsDeflectAlongTheirCurveFromTheGravityPreload) {
  const CellConfig c = hardening_case();
  ASSERT_EQ(c.robot.gravity_torque_nm.size(), 6u);
  const TrueRobot robot(c, false, 7);
  Workspace ws(robot.true_model());
  JointVector q(6);
  q << 0.1, deg_to_rad(25.0), deg_to_rad(5.0), 0.2, deg_to_rad(55.0), -0.3;
  for (double load : {150.0, 650.0}) {
    Wrench w;
    w << 0.6 * load, -0.5 * load, 0.6 * load, 0.0, 0.0, 0.0;
    TrueRobotState s = robot.initial_state(q);
    (void)robot.solve(ws, q, w, s);
    // The fixed point must satisfy q = q_cmd + C h(J(q)^T W), with h written out here.
    Jacobian J(6, 6);
    jacobian(robot.true_model(), ws, s.q_actual, EndPoint::kTcp, J);
    const JointVector tau = J.transpose() * w;
    JointVector h(6);
    for (int i = 0; i < 6; ++i) {
      const double sft = c.robot.hardening_softening[static_cast<std::size_t>(i)];
      const double th = c.robot.hardening_torque_nm[static_cast<std::size_t>(i)];
      const double g = c.robot.gravity_torque_nm[static_cast<std::size_t>(i)];
      h[i] = integrated_curve(sft, th, g + tau[i]) - integrated_curve(sft, th, g);
    }
    const JointVector expected = q + robot.joint_compliance() * h;
    EXPECT_NEAR((s.q_actual - expected).cwiseAbs().maxCoeff(), 0.0, 1e-9) << load;
    // Joint 1 (no preload) is measurably softer at 150 N than a linear gear would be.
    if (load == 150.0) {
      EXPECT_GT(std::abs(h[0] / tau[0]), 1.3);
    }
  }
}

// The fast computation's first-order end: a solve whose first step is small moves the end poses along
// the Jacobian instead of running the kinematics again. Checked against forward kinematics at the
// configuration it solved (a workspace of its own) and against the exact fixed point, tick by tick
// along a slow motion under 650 N; and the shortcut must really be taken (one FK a solve).
TEST(TrueRobot, AFirstOrderEndKeepsTheKinematicsOfTheSolvedConfiguration) {
  CellConfig c = hardening_case();
  CellConfig exact_config = c;
  c.robot.first_order_step_rad = 1e-5;
  const TrueRobot robot(c, false, 7);
  const TrueRobot exact(exact_config, false, 7);
  Workspace ws(robot.true_model()), ws_exact(exact.true_model()), ws_check(robot.true_model());
  JointVector q(6);
  q << 0.1, deg_to_rad(25.0), deg_to_rad(5.0), 0.2, deg_to_rad(55.0), -0.3;
  Wrench w;
  w << 390.0, -325.0, 390.0, 0.0, 0.0, 0.0;
  TrueRobotState s = robot.initial_state(q), s_exact = exact.initial_state(q);
  (void)robot.solve(ws, q, w, s);
  (void)exact.solve(ws_exact, q, w, s_exact);
  detail::kinematics_count.model = &robot.true_model();
  detail::kinematics_count.calls = 0;
  double worst_position = 0.0, worst_turn = 0.0, worst_tcp = 0.0;
  const int ticks = 200;
  for (int k = 1; k <= ticks; ++k) {
    JointVector dq(6);
    dq << 1.0, -0.7, 0.5, 1.3, -0.4, 0.9;
    q += 2e-5 * dq;  // ~40 um a tick at the TCP: 10 mm/s
    const Vector3 p = robot.solve(ws, q, w, s, 0.004);
    const Vector3 p_exact = exact.solve(ws_exact, q, w, s_exact, 0.004);
    forward_kinematics(exact.true_model(), ws_check, s.q_actual);
    worst_position = std::max({worst_position, (ws.base_T_tcp.translation() - ws_check.base_T_tcp.translation()).norm(),
                               (ws.base_T_flange.translation() - ws_check.base_T_flange.translation()).norm()});
    worst_turn = std::max({worst_turn, (ws.base_T_tcp.linear() - ws_check.base_T_tcp.linear()).cwiseAbs().maxCoeff(),
                           (ws.base_T_flange.linear() - ws_check.base_T_flange.linear()).cwiseAbs().maxCoeff()});
    worst_tcp = std::max(worst_tcp, (p - p_exact).norm());
  }
  detail::kinematics_count.model = nullptr;
  EXPECT_EQ(detail::kinematics_count.calls, static_cast<std::uint64_t>(ticks));  // one FK a solve
  EXPECT_LT(worst_position, 1e-9);                                               // m
  EXPECT_LT(worst_turn, 1e-9);
  // Against the exact fixed point: within the 30 nm the tolerance allows, and not bit-identical (the
  // test would prove nothing if the shortcut were never taken).
  EXPECT_LT(worst_tcp, 3e-8);
  EXPECT_GT(worst_tcp, 0.0);
}

TEST(PathDrift, OffsetAndWanderHaveTheConfiguredStatistics) {
  DriftConfig d;
  d.offset_m = 12e-6;
  d.rotation_rad = 3e-6;
  d.wander_m = 8e-6;
  d.wander_time_s = 3.0;
  const int runs = 4000;
  const double lag = 1.5;
  double so = 0, sr = 0, sw0 = 0, sw1 = 0, cross = 0;
  for (int k = 0; k < runs; ++k) {
    PathDrift p(d, 1000u + static_cast<std::uint64_t>(k));
    so += p.offset_m().squaredNorm();
    sr += p.rotation_rad().squaredNorm();
    const Vector3 w0 = p.wander_m();
    for (int i = 0; i < 375; ++i) p.advance(0.004);  // 1.5 s in servo ticks
    const Vector3 w1 = p.wander_m();
    sw0 += w0.squaredNorm();
    sw1 += w1.squaredNorm();
    cross += w0.dot(w1);
  }
  const double n = 3.0 * runs;
  EXPECT_NEAR(std::sqrt(so / n), 12e-6, 0.04 * 12e-6);
  EXPECT_NEAR(std::sqrt(sr / n), 3e-6, 0.04 * 3e-6);
  EXPECT_NEAR(std::sqrt(sw0 / n), 8e-6, 0.04 * 8e-6);
  EXPECT_NEAR(std::sqrt(sw1 / n), 8e-6, 0.04 * 8e-6);                     // stationary
  EXPECT_NEAR(cross / std::sqrt(sw0 * sw1), std::exp(-lag / 3.0), 0.03);  // OU autocorrelation
  // The rigid part: p + o + r x p.
  PathDrift p(d, 5);
  const Vector3 x(1.8, 0.2, 0.9);
  EXPECT_NEAR((p.apply(x) - (x + p.offset_m() + p.rotation_rad().cross(x) + p.wander_m())).norm(), 0.0, 1e-15);
  DriftConfig off;
  PathDrift none(off, 5);
  none.advance(1.0);
  EXPECT_FALSE(none.active());
  EXPECT_EQ((none.apply(x) - x).norm(), 0.0);
}

TEST(ForceSensorDaq, UnknownSensitivityAndMisalignmentGiveTheExpectedReading) {
  SensorConfig s;
  s.crosstalk = 0.0;
  s.crosstalk_calibration_residual = 0.0;
  s.noise_n = 0.0;
  s.sensitivity_error = 0.01;
  s.misalignment_rad = deg_to_rad(0.75);
  ForceSensorDaq daq(s, ToolConfig{}, 3, 11);
  const Vector3 S = daq.sensitivity();
  const double g = deg_to_rad(0.75);
  // A force along the flange x axis reads in a frame turned by +g about z: (cos g, -sin g, 0).
  const Vector3 f = daq.sample(Vector3(100.0, 0.0, 0.0), Matrix3::Identity());
  EXPECT_NEAR(f.x(), S.x() * 100.0 * std::cos(g), 1e-9);
  EXPECT_NEAR(f.y(), -S.y() * 100.0 * std::sin(g), 1e-9);
  EXPECT_NEAR(f.z(), 0.0, 1e-9);
  const Vector3 fz = daq.sample(Vector3(0.0, 0.0, 50.0), Matrix3::Identity());
  EXPECT_NEAR(fz.z(), S.z() * 50.0, 1e-9);
  // The user's decoupling knows neither: the decoupled reading is off by exactly this much.
  EXPECT_NEAR((daq.calibration().decoupling - Matrix3::Identity()).norm(), 0.0, 1e-15);
  // The same physical sensor in every run (unit seed), whatever the run's noise seed.
  ForceSensorDaq other_run(s, ToolConfig{}, 99, 11);
  EXPECT_EQ(other_run.sensitivity(), S);
  // Sensitivity errors have the configured 1-sigma over many sensors.
  double sum2 = 0;
  const int units = 3000;
  for (int k = 0; k < units; ++k) {
    ForceSensorDaq u(s, ToolConfig{}, 1, 500u + static_cast<std::uint64_t>(k));
    sum2 += (u.sensitivity() - Vector3::Ones()).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(sum2 / (3.0 * units)), 0.01, 0.0005);
}

}  // namespace
}  // namespace deflex::cell
