// The compensation cycle: corrections against the lumped model computed here with a finite-difference
// Jacobian, the size and rate bounds, the watchdog ramp, faults, invalid input, and no allocation.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "deflex/online/online_compensator.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "online/fd_jacobian.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

JointVector model_dtheta(const RobotModel& m, const JointVector& q, const Wrench& w) {
  const Jacobian J = test::fd_wap_jacobian(m, q);
  JointVector d = J.transpose() * w;
  for (int i = 0; i < m.dof(); ++i) {
    d[i] /= m.stiffness()[i];
  }
  return d;
}

JointVector deg(std::initializer_list<double> v) {
  JointVector q(static_cast<Eigen::Index>(v.size()));
  int i = 0;
  for (double x : v) {
    q[i++] = deg_to_rad(x);
  }
  return q;
}

SensorConfig flange_sensor() {
  SensorConfig c;
  c.components = 6;
  c.sample_rate_hz = 250.0;
  c.lowpass_cutoff_hz = 25.0;
  c.fault_threshold_N = 3000.0;
  return c;
}

ForceSample force_at_wap_sensor_frame(const RobotModel& m, const JointVector& q, const Vector3& f_base) {
  // With the sensor at the flange and the WAP at the TCP: the reading in the sensor (flange) frame.
  Workspace ws(m);
  forward_kinematics(m, ws, q);
  const Matrix3 R = ws.base_T_flange.linear();
  const Vector3 f_s = R.transpose() * f_base;
  const Vector3 wap_s = m.flange_T_wap().translation();
  ForceSample s;
  s.wrench_sensor.head<3>() = f_s;
  s.wrench_sensor.tail<3>() = wap_s.cross(f_s);
  return s;
}

class Compensator : public ::testing::Test {
 protected:
  RobotModel robot = [] {
    Pose tool = Pose::Identity();
    tool.translation() = Vector3(0.02, 0.0, 0.30);
    return builtin_irb6700().with_tool(tool);
  }();
  OnlineConfig cfg = [] {
    OnlineConfig c;
    c.period_s = 0.004;
    c.max_correction_rate_rad_s = 1.0;
    c.max_tcp_rate_m_s = 10.0;  // the joint rate bound is the one these tests look at
    return c;
  }();
  JointVector q = deg({10, 20, -10, 30, 40, -20});
};

TEST_F(Compensator, CorrectionMatchesTheModel) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  const Vector3 f(150, -300, 500);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, f);
  CycleOutput out;
  for (int k = 0; k < 10; ++k) {
    comp.push_force(s);
    out = comp.step({0.004 * k, q, q});
  }
  ASSERT_EQ(out.status, CycleStatus::kOk);
  Wrench w;
  w << f, Vector3::Zero();
  const JointVector expected = model_dtheta(robot, q, w);
  EXPECT_LT((out.dtheta - expected).norm(), 1e-8 * expected.norm() + 1e-12) << out.dtheta.transpose() << "\n"
                                                                            << expected.transpose();
  EXPECT_LT((out.q_command - (q - expected)).norm(), 1e-8 * expected.norm() + 1e-12);
  EXPECT_GT(expected.norm(), 1e-5);  // a real correction, not zero
  EXPECT_FALSE(out.size_limited);
}

TEST_F(Compensator, JacobianAtPlannedOrFeedback) {
  const JointVector q_fb = q + deg({0.5, -0.3, 0.2, 0.0, 0.4, 0.1});
  const Vector3 f(0, 0, -600);
  for (JacobianAt at : {JacobianAt::kPlanned, JacobianAt::kFeedback}) {
    OnlineConfig c = cfg;
    c.jacobian_at = at;
    OnlineCompensator comp(robot, flange_sensor(), c);
    const ForceSample s = force_at_wap_sensor_frame(robot, q_fb, f);  // the sensor is where the arm is
    CycleOutput out;
    for (int k = 0; k < 10; ++k) {
      comp.push_force(s);
      out = comp.step({0.004 * k, q, q_fb});
    }
    Wrench w;
    w << f, Vector3::Zero();
    // Moment: the force still acts at the WAP whose position depends on q_fb vs q only through the
    // lever, which the pipeline takes from the sensor reading; the wrench at the WAP is pure force.
    const JointVector expected = model_dtheta(robot, at == JacobianAt::kPlanned ? q : q_fb, w);
    EXPECT_LT((out.dtheta - expected).norm(), 1e-8 * expected.norm()) << static_cast<int>(at);
  }
}

TEST_F(Compensator, SizeBoundsHoldAndKeepDirection) {
  OnlineConfig c = cfg;
  c.max_tcp_correction_m = 0.0002;
  c.max_correction_rate_rad_s = 100.0;
  OnlineCompensator comp(robot, flange_sensor(), c);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, Vector3(0, 2000, 0));
  CycleOutput out;
  for (int k = 0; k < 5; ++k) {
    comp.push_force(s);
    out = comp.step({0.004 * k, q, q});
  }
  EXPECT_TRUE(out.size_limited);
  EXPECT_NEAR(out.tcp_correction_m, 0.0002, 1e-9);
  Wrench w;
  w << 0, 2000, 0, 0, 0, 0;
  const JointVector full = model_dtheta(robot, q, w);
  EXPECT_NEAR(out.dtheta.normalized().dot(full.normalized()), 1.0, 1e-9);

  OnlineConfig c2 = cfg;
  c2.max_joint_correction_rad = 1e-5;
  c2.max_correction_rate_rad_s = 100.0;
  OnlineCompensator comp2(robot, flange_sensor(), c2);
  for (int k = 0; k < 5; ++k) {
    comp2.push_force(s);
    out = comp2.step({0.004 * k, q, q});
  }
  EXPECT_LE(out.dtheta.cwiseAbs().maxCoeff(), 1e-5 + 1e-15);
  EXPECT_TRUE(out.size_limited);
}

TEST_F(Compensator, RateBoundAndWatchdogRampToZero) {
  OnlineConfig c = cfg;
  c.max_correction_rate_rad_s = 0.01;  // 4e-5 rad a cycle
  c.watchdog_s = 0.02;
  OnlineCompensator comp(robot, flange_sensor(), c);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, Vector3(0, 0, -900));
  JointVector prev = JointVector::Zero(6);
  CycleOutput out;
  double t = 0.0;
  bool limited = false;
  for (int k = 0; k < 100; ++k, t += 0.004) {
    comp.push_force(s);
    out = comp.step({t, q, q});
    EXPECT_LE((out.dtheta - prev).cwiseAbs().maxCoeff(), 0.01 * 0.004 + 1e-15);
    limited = limited || out.rate_limited;
    prev = out.dtheta;
  }
  EXPECT_TRUE(limited);
  EXPECT_EQ(out.status, CycleStatus::kOk);
  const double start = out.dtheta.cwiseAbs().maxCoeff();
  ASSERT_GT(start, 1e-5);
  // The sensor goes silent: after the watchdog time the correction ramps down at the rate bound.
  int stale_cycles = 0;
  for (int k = 0; k < 200; ++k, t += 0.004) {
    out = comp.step({t, q, q});
    EXPECT_LE((out.dtheta - prev).cwiseAbs().maxCoeff(), 0.01 * 0.004 + 1e-15);
    EXPECT_LE(out.dtheta.cwiseAbs().maxCoeff(), prev.cwiseAbs().maxCoeff() + 1e-15);
    if (out.status == CycleStatus::kStaleForce) {
      ++stale_cycles;
    }
    prev = out.dtheta;
  }
  EXPECT_GT(stale_cycles, 150);
  EXPECT_TRUE(out.dtheta.isZero(0.0));
  EXPECT_TRUE(out.q_command.isApprox(q, 0.0) || (out.q_command - q).norm() == 0.0);
}

TEST_F(Compensator, FaultSampleNeverMovesTheRobot) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  const ForceSample ok = force_at_wap_sensor_frame(robot, q, Vector3(0, 0, -500));
  ForceSample bad = ok;
  bad.wrench_sensor *= 20.0;  // 10 kN: above the 3 kN fault threshold
  CycleOutput out;
  double t = 0;
  for (int k = 0; k < 10; ++k, t += 0.004) {
    comp.push_force(ok);
    out = comp.step({t, q, q});
  }
  const JointVector before = out.dtheta;
  comp.push_force(bad);
  out = comp.step({t, q, q});
  t += 0.004;
  EXPECT_EQ(out.status, CycleStatus::kForceFault);
  EXPECT_LE(out.dtheta.norm(), before.norm());  // only towards zero
  for (int k = 0; k < 50; ++k, t += 0.004) {
    comp.push_force(ok);
    out = comp.step({t, q, q});
  }
  EXPECT_EQ(out.status, CycleStatus::kForceFault);  // held for fault_hold_s = 0.5 s
  EXPECT_TRUE(out.dtheta.isZero(0.0));
  EXPECT_EQ(comp.counters().samples_fault, 1u);
}

TEST_F(Compensator, InvalidInputsNeverProduceACommand) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  JointVector qn = q;
  qn[2] = std::nan("");
  EXPECT_EQ(comp.step({0.0, qn, q}).status, CycleStatus::kInvalidInput);
  EXPECT_EQ(comp.step({0.0, q, qn}).status, CycleStatus::kInvalidInput);
  EXPECT_EQ(comp.step({0.0, q.head(5), q.head(5)}).status, CycleStatus::kInvalidInput);
  EXPECT_EQ(comp.step({std::nan(""), q, q}).status, CycleStatus::kInvalidInput);
  ForceSample s = force_at_wap_sensor_frame(robot, q, Vector3(0, 0, -500));
  s.wrench_sensor[1] = std::numeric_limits<double>::infinity();
  comp.push_force(s);
  const CycleOutput out = comp.step({0.0, q, q});
  EXPECT_EQ(out.status, CycleStatus::kNoForceYet);
  EXPECT_TRUE(out.q_command.allFinite());
  EXPECT_EQ(out.q_command, q);
  EXPECT_EQ(comp.counters().samples_invalid, 1u);
  EXPECT_THROW(OnlineCompensator(robot, flange_sensor(),
                                 [] {
                                   OnlineConfig c;
                                   c.watchdog_s = -1;
                                   return c;
                                 }()),
               InputError);
}

// Joints beyond the robot file's limits (joint 1 of the IRB 6700: +-170 deg) are a status, never a
// command: a planned q1 of 10 rad (a program in the wrong unit), feedback beyond a limit, and a
// correction that would take a joint at its limit past it.
TEST_F(Compensator, JointsBeyondTheLimitsAreAStatusNotACommand) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, Vector3(150, -300, 500));
  CycleOutput out;
  double t = 0.0;
  for (int k = 0; k < 20; ++k, t += 0.004) {
    comp.push_force(s);
    out = comp.step({t, q, q});
  }
  ASSERT_EQ(out.status, CycleStatus::kOk);
  JointVector far = q;
  far[0] = 10.0;
  {
    test::AllocationGuard guard;
    out = comp.step({t, far, far});
  }
  EXPECT_EQ(out.status, CycleStatus::kOutsideLimits);
  EXPECT_LT(static_cast<int>(out.status), 0);           // not usable: q_command must not be sent
  EXPECT_LT(out.q_command.cwiseAbs().maxCoeff(), 1.0);  // nothing near 10 rad comes out
  EXPECT_STREQ(to_string(out.status), "outside_limits");
  t += 0.004;
  EXPECT_EQ(comp.step({t, q, far}).status, CycleStatus::kOutsideLimits);  // the feedback beyond
  t += 0.004;
  EXPECT_EQ(comp.step({t, q, q}).status, CycleStatus::kOk);  // back inside: corrections again
  EXPECT_EQ(comp.counters().invalid_inputs, 2u);

  // Joint 2 at the limit its correction points away from (the model's dtheta computed here by finite
  // differences): q_command = q - dtheta would leave the limits.
  Vector3 f(150, -300, 500);
  JointVector edge = q;
  edge[1] = robot.upper_limits()[1];
  Wrench w = Wrench::Zero();
  w.head<3>() = f;
  if (model_dtheta(robot, edge, w)[1] > 0.0) {
    edge[1] = robot.lower_limits()[1];
    if (model_dtheta(robot, edge, w)[1] < 0.0) f = -f;
  }
  OnlineCompensator at_edge(robot, flange_sensor(), cfg);
  at_edge.push_force(force_at_wap_sensor_frame(robot, edge, f));
  out = at_edge.step({0.0, edge, edge});
  EXPECT_EQ(out.status, CycleStatus::kOutsideLimits);
  EXPECT_TRUE(out.q_command.isZero(0.0));
}

TEST_F(Compensator, RandomisedPropertiesHold) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  OnlineConfig c = cfg;
  c.max_tcp_correction_m = 0.001;
  c.max_joint_correction_rad = 0.002;
  c.max_correction_rate_rad_s = 0.05;
  OnlineCompensator comp(robot, flange_sensor(), c);
  JointVector prev = JointVector::Zero(6);
  for (int k = 0; k < 2000; ++k) {
    JointVector qk(6);
    for (int i = 0; i < 6; ++i) {
      const double lo = robot.lower_limits()[i], hi = robot.upper_limits()[i];
      qk[i] = 0.5 * (lo + hi) + 0.45 * (hi - lo) * u(rng);
    }
    ForceSample s;
    for (int i = 0; i < 6; ++i) {
      s.wrench_sensor[i] = (i < 3 ? 2500.0 : 300.0) * u(rng);
    }
    comp.push_force(s);
    const CycleOutput out = comp.step({0.004 * k, qk, qk});
    ASSERT_TRUE(out.q_command.allFinite());
    EXPECT_LE(out.dtheta.cwiseAbs().maxCoeff(), 0.002 + 1e-15);
    EXPECT_LE((out.dtheta - prev).cwiseAbs().maxCoeff(), 0.05 * 0.004 + 1e-15);
    EXPECT_LT((out.q_command - (qk - out.dtheta)).norm(), 1e-15);
    prev = out.dtheta;
  }
}

TEST_F(Compensator, WrenchOffsetAndLeadAreAppliedBeforeTheModel) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  const Vector3 f(150, -300, 500);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, f);
  Wrench offset = Wrench::Zero();
  offset.head<3>() = Vector3(-50, 20, 10);
  CycleInput in{0.0, q, q};
  in.wrench_offset_base = offset;
  CycleOutput out;
  for (int k = 0; k < 30; ++k) {
    comp.push_force(s);
    in.t_s = 0.004 * k;
    out = comp.step(in);
  }
  Wrench used = Wrench::Zero();
  used.head<3>() = f + offset.head<3>();
  EXPECT_LT((out.dtheta - model_dtheta(robot, q, used)).norm(), 1e-9 * model_dtheta(robot, q, used).norm() + 1e-12);
  EXPECT_LT((out.wrench_measured_base.head<3>() - f).norm(), 1e-9);
  // A force rising at 1000 N/s along x: with a 0.05 s lead the model sees 50 N more than measured.
  OnlineCompensator ramp(robot, flange_sensor(), cfg);
  CycleInput r{0.0, q, q};
  r.wrench_lead_s = 0.05;
  for (int k = 0; k < 200; ++k) {
    r.t_s = 0.004 * k;
    ramp.push_force(force_at_wap_sensor_frame(robot, q, Vector3(100.0 + 1000.0 * r.t_s, 0, 0)));
    out = ramp.step(r);
  }
  EXPECT_NEAR(ramp.wrench_slope()[0], 1000.0, 1.0);
  EXPECT_NEAR(out.wrench_base[0] - out.wrench_measured_base[0], 50.0, 0.1);
  // The filter's lag is the 25 Hz second-order Butterworth's: sqrt(2) / (2 pi 25) s for the analog
  // prototype; the digital one at 250 Hz within a few percent of it.
  EXPECT_NEAR(ramp.filter_delay_s(), std::sqrt(2.0) / (2.0 * kPi * 25.0), 0.05 * std::sqrt(2.0) / (2.0 * kPi * 25.0));
  // And it is what the filtered ramp lags by: measured = 100 + 1000 (t - lag).
  EXPECT_NEAR(out.wrench_measured_base[0], 100.0 + 1000.0 * (r.t_s - ramp.filter_delay_s()), 0.05);
}

TEST_F(Compensator, HoldToZeroRampsTheCorrectionDown) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, Vector3(0, 0, -600));
  CycleInput in{0.0, q, q};
  CycleOutput out;
  for (int k = 0; k < 50; ++k) {
    comp.push_force(s);
    in.t_s = 0.004 * k;
    out = comp.step(in);
  }
  ASSERT_GT(out.dtheta.cwiseAbs().maxCoeff(), 1e-5);
  in.hold_to_zero = true;
  double previous = out.dtheta.cwiseAbs().maxCoeff();
  for (int k = 50; k < 400; ++k) {
    comp.push_force(s);
    in.t_s = 0.004 * k;
    out = comp.step(in);
    EXPECT_EQ(out.status, CycleStatus::kHeld);
    EXPECT_LE(out.dtheta.cwiseAbs().maxCoeff(), previous);
    EXPECT_LE(previous - out.dtheta.cwiseAbs().maxCoeff(), cfg.max_correction_rate_rad_s * 0.004 + 1e-15);
    previous = out.dtheta.cwiseAbs().maxCoeff();
  }
  EXPECT_EQ(out.dtheta.cwiseAbs().maxCoeff(), 0.0);
  in.wrench_offset_base[0] = std::nan("");
  EXPECT_EQ(comp.step(in).status, CycleStatus::kInvalidInput);
}

TEST_F(Compensator, SteadyStateCycleDoesNotAllocate) {
  OnlineCompensator comp(robot, flange_sensor(), cfg);
  const ForceSample s = force_at_wap_sensor_frame(robot, q, Vector3(10, 20, -500));
  CycleInput in{0.0, q, q};
  (void)comp.step(in);
  test::AllocationGuard guard;
  for (int k = 1; k < 500; ++k) {
    in.t_s = 0.004 * k;
    comp.push_force(s);
    const CycleOutput out = comp.step(in);
    ASSERT_GE(static_cast<int>(out.status), 0);
  }
  // Stale, fault, invalid paths too.
  for (int k = 500; k < 600; ++k) {
    in.t_s = 0.004 * k;
    (void)comp.step(in);
  }
  in.q_planned[0] = std::nan("");
  (void)comp.step(in);
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
