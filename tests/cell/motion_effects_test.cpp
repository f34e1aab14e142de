// The cell's effects beyond the lumped model, against closed forms and their stated statistics:
// upper-arm bending (reciprocity and 1/EI), the foundation's tilt, stiffness that depends on the
// joints' motion, the servos' following error and yield, the sensor's zero drift, the LDBB's
// stick-slip, the thermal drift of loaded runs and the session's slow drift between runs.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Eigenvalues>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/model/kinematics.hpp"

namespace deflex::cell {
namespace {

CellConfig effects_cell() {
  CellConfig c;
  c.robot.gravity_torque_nm = {0, 9000, 3500, 0, 60, 0};
  return c;
}

JointVector effects_pose() {
  JointVector q(6);
  q << 0.1, deg_to_rad(25.0), deg_to_rad(5.0), 0.2, deg_to_rad(55.0), -0.3;
  return q;
}

// The 3x3 compliance of a structural effect at the TCP: column i is the displacement under 1 N
// along base axis i (the effect is linear in the force).
Matrix3 structural_compliance(const TrueRobot& robot, Workspace& ws) {
  Matrix3 C;
  for (int i = 0; i < 3; ++i) {
    Wrench w = Wrench::Zero();
    w[i] = 1.0;
    C.col(i) = robot.structural_displacement(ws, w);
  }
  return C;
}

TEST(TrueRobot, UpperArmBendingIsReciprocalPositiveAndGoesWithOneOverEI) {
  CellConfig c = effects_cell();
  c.robot.upper_arm_ei_nm2 = 4e7;
  const TrueRobot robot(c, false, 7);
  Workspace ws(robot.true_model());
  forward_kinematics(robot.true_model(), ws, effects_pose());
  const Matrix3 C = structural_compliance(robot, ws);
  // Maxwell-Betti: a linear elastic structure's compliance is symmetric, and it stores energy under
  // any force that bends it (positive semi-definite).
  EXPECT_NEAR((C - C.transpose()).norm(), 0.0, 1e-6 * C.norm());
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(0.5 * (C + C.transpose()));
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * C.norm());
  EXPECT_GT(eig.eigenvalues().maxCoeff(), 1e-9);  // about 0.1 um/N for this arm: not nothing
  // Half the bending stiffness, twice the deflection.
  CellConfig soft = c;
  soft.robot.upper_arm_ei_nm2 = 2e7;
  const TrueRobot soft_robot(soft, false, 7);
  Workspace ws2(soft_robot.true_model());
  forward_kinematics(soft_robot.true_model(), ws2, effects_pose());
  EXPECT_NEAR((structural_compliance(soft_robot, ws2) - 2.0 * C).norm(), 0.0, 1e-9 * C.norm());
  // EI 0 stands for a rigid arm: nothing added.
  CellConfig rigid = effects_cell();
  const TrueRobot rigid_robot(rigid, false, 7);
  Workspace ws3(rigid_robot.true_model());
  forward_kinematics(rigid_robot.true_model(), ws3, effects_pose());
  EXPECT_EQ(structural_compliance(rigid_robot, ws3).norm(), 0.0);
}

TEST(TrueRobot, FoundationTiltMovesTheTcpByTheMomentAboutTheBase) {
  CellConfig c = effects_cell();
  const double k = 3e-10;  // rad/Nm
  c.robot.base_tilt_compliance_rad_per_nm = k;
  const TrueRobot robot(c, false, 7);
  Workspace ws(robot.true_model());
  forward_kinematics(robot.true_model(), ws, effects_pose());
  const Vector3 p = ws.base_T_tcp.translation();
  // A vertical force F at the TCP, at horizontal distance r and height h from the base origin: the
  // foundation tilts by k F r about the horizontal axis across the arm, which lowers the TCP by
  // k F r^2 and moves it outwards by k F r h.
  const double F = 1000.0;
  Wrench w = Wrench::Zero();
  w[2] = -F;
  const Vector3 d = robot.structural_displacement(ws, w);
  const double r = std::hypot(p.x(), p.y());
  const Vector3 radial(p.x() / r, p.y() / r, 0.0);
  EXPECT_NEAR(d.z(), -k * F * r * r, 1e-12);
  EXPECT_NEAR(d.dot(radial), k * F * r * p.z(), 1e-12);
  EXPECT_NEAR((d - d.dot(radial) * radial - d.z() * Vector3::UnitZ()).norm(), 0.0, 1e-15);
}

// TCP displacement from the unloaded pose (same motion) under a wrench, with the joints moving at
// `speed` rad/s each for a few ticks of dt.
Vector3 moving_deflection(const TrueRobot& robot, const JointVector& speed, const Wrench& w) {
  Workspace ws(robot.true_model());
  const double dt = 0.004;
  JointVector q = effects_pose();
  TrueRobotState loaded = robot.initial_state(q), unloaded = robot.initial_state(q);
  Vector3 d = Vector3::Zero();
  for (int i = 1; i <= 5; ++i) {
    q += speed * dt;
    const Vector3 pl = robot.solve(ws, q, w, loaded, dt);
    const Vector3 pu = robot.solve(ws, q, Wrench::Zero(), unloaded, dt);
    d = pl - pu;
  }
  return d;
}

TEST(TrueRobot, MovingJointsDeflectLessAndMoreWithTheirTorque) {
  CellConfig c = effects_cell();
  c.robot.lost_motion_rad.clear();  // lost motion would add its own direction-dependent offset
  const TrueRobot still(c, false, 7);
  c.robot.speed_stiffening = 0.10;
  c.robot.speed_ref_rad_s = 1e-4;  // so that tanh(|v| / v_ref) = 1 at the speeds below
  const TrueRobot stiffening(c, false, 7);
  Wrench w;
  w << 300.0, -200.0, 500.0, 0.0, 0.0, 0.0;
  const JointVector zero = JointVector::Zero(6);
  const JointVector v = JointVector::Constant(6, 0.05);
  // Every joint moving: each joint's deflection is 90 % of the still arm's, so the TCP's too (to
  // first order; the fixed point's geometry changes a little with the smaller deflection).
  const Vector3 d_still = moving_deflection(still, zero, w);
  const Vector3 d_moving = moving_deflection(stiffening, v, w);
  EXPECT_NEAR((d_moving - 0.9 * d_still).norm(), 0.0, 0.01 * d_still.norm());
  // At rest the stiffening arm is the still one.
  EXPECT_NEAR((moving_deflection(stiffening, zero, w) - d_still).norm(), 0.0, 1e-12);
  // Direction asymmetry: moving with the torque of every joint yields (1 + a), against it (1 - a);
  // the mean of the two is the still arm's.
  CellConfig a = effects_cell();
  a.robot.lost_motion_rad.clear();
  a.robot.direction_asymmetry = 0.08;
  a.robot.speed_ref_rad_s = 1e-4;
  const TrueRobot asym(a, false, 7);
  Workspace ws(asym.true_model());
  Jacobian J(6, 6);
  jacobian(asym.true_model(), ws, effects_pose(), EndPoint::kTcp, J);
  const JointVector tau = J.transpose() * w;
  const JointVector with = 0.05 * tau.cwiseSign();
  const Vector3 d_with = moving_deflection(asym, with, w);
  const Vector3 d_against = moving_deflection(asym, -with, w);
  EXPECT_NEAR((d_with - 1.08 * d_still).norm(), 0.0, 0.01 * d_still.norm());
  EXPECT_NEAR((d_against - 0.92 * d_still).norm(), 0.0, 0.01 * d_still.norm());
}

TEST(TrueRobot, ServoFollowingErrorAndItsYieldToAChangingTorque) {
  CellConfig c = effects_cell();
  c.robot.lost_motion_rad.clear();
  c.robot.servo_following_s = 0.008;
  const TrueRobot robot(c, false, 7);
  Workspace ws(robot.true_model());
  const double dt = 0.004;
  JointVector q = effects_pose();
  TrueRobotState s = robot.initial_state(q);
  const JointVector v = JointVector::Constant(6, 0.1);
  for (int i = 0; i < 3; ++i) {
    q += v * dt;
    (void)robot.solve(ws, q, Wrench::Zero(), s, dt);
  }
  // The motors lag their command by the following time times the speed.
  EXPECT_NEAR((s.q_motor - (q - 0.008 * v)).norm(), 0.0, 1e-12);

  // The yield: a process torque that steps on yields f C dtau more at first, decaying with the
  // integral action's time constant: after n ticks the integrator holds 1 - exp(-n dt / T_i) of it.
  CellConfig y = effects_cell();
  y.robot.lost_motion_rad.clear();
  const TrueRobot rigid_servo(y, false, 7);
  const double f = 0.2, Ti = 0.1;
  y.robot.servo_compliance_fraction = f;
  y.robot.servo_integral_s = Ti;
  const TrueRobot yielding(y, false, 7);
  const JointVector q0 = effects_pose();
  TrueRobotState sy = yielding.initial_state(q0), sr = rigid_servo.initial_state(q0);
  Workspace wy(yielding.true_model()), wr(rigid_servo.true_model());
  (void)yielding.solve(wy, q0, Wrench::Zero(), sy, dt);  // unloaded: the integrator holds no torque
  (void)rigid_servo.solve(wr, q0, Wrench::Zero(), sr, dt);
  Wrench w;
  w << 300.0, -200.0, 500.0, 0.0, 0.0, 0.0;
  const JointVector k = yielding.true_model().stiffness();
  for (int n = 1; n <= 25; ++n) {
    (void)yielding.solve(wy, q0, w, sy, dt);
    (void)rigid_servo.solve(wr, q0, w, sr, dt);
    if (n != 1 && n != 25) continue;
    Jacobian J(6, 6);
    jacobian(rigid_servo.true_model(), wr, sr.q_actual, EndPoint::kTcp, J);
    const JointVector tau = J.transpose() * w;
    const JointVector expected = f * tau.cwiseQuotient(k) * std::exp(-n * dt / Ti);
    EXPECT_NEAR((sy.q_actual - sr.q_actual - expected).norm(), 0.0, 0.02 * expected.norm()) << "tick " << n;
  }
}

TEST(ForceSensorDaq, ZeroDriftGrowsLinearlyWithTheStatedSpreadPerTenMinutes) {
  SensorConfig s;
  s.noise_n = 0.0;
  s.crosstalk = 0.0;
  s.zero_drift_n = 0.4;
  ToolConfig tool;
  tool.ee_mass_kg = 0.0;
  double sum2 = 0.0;
  const int runs = 3000;
  for (int k = 0; k < runs; ++k) {
    ForceSensorDaq daq(s, tool, 100u + static_cast<std::uint64_t>(k), 1);
    const Vector3 at0 = daq.sample(Vector3::Zero(), Matrix3::Identity(), 0.0);
    const Vector3 at300 = daq.sample(Vector3::Zero(), Matrix3::Identity(), 300.0);
    const Vector3 at600 = daq.sample(Vector3::Zero(), Matrix3::Identity(), 600.0);
    EXPECT_NEAR(((at300 - at0) - 0.5 * (at600 - at0)).norm(), 0.0, 1e-12);  // linear in time
    sum2 += (at600 - at0).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(sum2 / (3.0 * runs)), 0.4, 0.04 * 0.4);
}

TEST(LdbbDevice, StickSlipIsASawtoothOverThePistonsTravel) {
  // The bar along +z from the origin; the TCP moves 0.1 mm a tick along it, out then back: the piston
  // travels 0.1 mm a tick either way, so a 1 mm tooth takes ten ticks: the force rises over nine and
  // slips back over the tenth, whichever way the piston goes. The TCP moving across the bar does not
  // slide the piston and leaves the sawtooth where it is.
  LdbbConfig c;
  c.bar_length_m = 0.15;
  c.time_constant_s = 0.3;
  c.ripple = 0.0;
  c.noise = 0.0;
  c.ball_friction = 0.0;
  c.stick_slip = 0.1;
  c.stick_slip_travel_m = 0.001;
  LdbbDevice d(c, Vector3::Zero(), 500.0, 1);
  d.settle();
  auto expected = [](double travel_m) {
    const double x = travel_m / 0.001 - std::floor(travel_m / 0.001 + 1e-9);
    const double shape = x < 0.9 ? x / 0.9 : (1.0 - x) / 0.1;
    return 500.0 * (1.0 + 0.1 * (shape - 0.5));
  };
  EXPECT_NEAR(d.wrench(Vector3(0, 0, 0.15), Vector3::Zero())[2], expected(0.0), 1e-6);
  for (int i = 1; i <= 25; ++i) {
    const double out = i <= 15 ? i : 30 - i;  // out for 15 ticks, then back
    EXPECT_NEAR(d.wrench(Vector3(0, 0, 0.15 + 1e-4 * out), Vector3(0, 0, 0.025))[2], expected(1e-4 * i), 1e-6)
        << "tick " << i;
  }
  // Swinging the bar about the pivot at its length: the force's size stays, its direction turns.
  const double before = d.wrench(Vector3(0, 0, 0.151), Vector3::Zero()).head<3>().norm();
  const double a = 0.03;
  const Wrench swung = d.wrench(0.151 * Vector3(std::sin(a), 0, std::cos(a)), Vector3(0.151 * a / 0.004, 0, 0));
  EXPECT_NEAR(swung.head<3>().norm(), before, 1e-9);
  EXPECT_NEAR(swung[0] / swung[2], std::tan(a), 1e-12);
}

TEST(PathDrift, LoadedRunsWarmMoreWithTheSquareOfTheLoad) {
  DriftConfig d;
  d.load_offset_m = 15e-6;
  d.load_reference_n = 650.0;
  const int runs = 3000;
  double at_ref = 0.0, at_half = 0.0;
  for (int k = 0; k < runs; ++k) {
    at_ref += PathDrift(d, 50u + static_cast<std::uint64_t>(k), 650.0).load_offset_m().squaredNorm();
    at_half += PathDrift(d, 50u + static_cast<std::uint64_t>(k), 325.0).load_offset_m().squaredNorm();
    EXPECT_EQ(PathDrift(d, 50u + static_cast<std::uint64_t>(k), 0.0).load_offset_m().norm(), 0.0);
  }
  EXPECT_NEAR(std::sqrt(at_ref / (3.0 * runs)), 15e-6, 0.04 * 15e-6);
  EXPECT_NEAR(std::sqrt(at_half / (3.0 * runs)), 0.25 * 15e-6, 0.04 * 0.25 * 15e-6);
}

TEST(PathDrift, ASessionsRunsShareTheirSlowDriftByTheirDistanceInTime) {
  DriftConfig d;
  d.offset_m = 12e-6;
  d.offset_time_s = 1200.0;
  const int runs = 4000;
  double s0 = 0.0, s1 = 0.0, cross = 0.0, cross_far = 0.0, s_far = 0.0;
  for (int k = 0; k < runs; ++k) {
    const PathDrift first(d, 7000u + static_cast<std::uint64_t>(k));
    const PathDrift next(d, 9000u + static_cast<std::uint64_t>(k), first, 1200.0);
    const PathDrift far(d, 11000u + static_cast<std::uint64_t>(k), first, 1e6);
    s0 += first.offset_m().squaredNorm();
    s1 += next.offset_m().squaredNorm();
    s_far += far.offset_m().squaredNorm();
    cross += first.offset_m().dot(next.offset_m());
    cross_far += first.offset_m().dot(far.offset_m());
  }
  EXPECT_NEAR(std::sqrt(s1 / (3.0 * runs)), 12e-6, 0.04 * 12e-6);  // stationary
  EXPECT_NEAR(cross / std::sqrt(s0 * s1), std::exp(-1.0), 0.03);   // one correlation time apart
  EXPECT_NEAR(cross_far / std::sqrt(s0 * s_far), 0.0, 0.04);       // independent
  // No time between them: the same offset.
  const PathDrift a(d, 3);
  const PathDrift b(d, 4, a, 0.0);
  EXPECT_NEAR((a.offset_m() - b.offset_m()).norm(), 0.0, 1e-18);
}

}  // namespace
}  // namespace deflex::cell
