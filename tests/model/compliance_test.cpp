// The lumped joint-compliance model against closed forms (two-link planar arm), finite differences
// (complementary stiffness) and its own exactness claims (compensation), and the no-allocation
// guarantee of every hot call.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "deflex/model/compliance.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "online/fd_jacobian.hpp"
#include "support/allocation_guard.hpp"
#include "test_robots.hpp"

namespace deflex {
namespace {

constexpr double kL1 = 0.8;
constexpr double kL2 = 0.6;
constexpr double kK1 = 2.0e5;
constexpr double kK2 = 5.0e4;

RobotModel two_link() {
  return load_robot_yaml_text(R"(
deflex_robot: 1
name: planar two-link
units: {length: m, angle: rad}
kinematics:
  convention: standard_dh
  joints:
    - {a: 0.8, alpha: 0, d: 0, min: -3, max: 3}
    - {a: 0.6, alpha: 0, d: 0, min: -3, max: 3}
joint_stiffness_Nm_per_rad: [2.0e5, 5.0e4]
)",
                              "two-link");
}

TEST(Compliance, TwoLinkPlanarMatchesClosedForm) {
  const RobotModel m = two_link();
  Workspace ws(m);
  for (const auto& [t1, t2] : {std::pair{0.3, 0.9}, std::pair{-1.1, 2.0}, std::pair{2.5, -0.4}}) {
    JointVector q(2);
    q << t1, t2;
    const double fx = 120.0;
    const double fy = -75.0;
    const double mz = 14.0;
    Wrench w;
    w << fx, fy, 0, 0, 0, mz;
    // Closed form: tau = J^T W for the planar arm; the moment acts on both joints.
    const double s1 = std::sin(t1), c1 = std::cos(t1), s12 = std::sin(t1 + t2), c12 = std::cos(t1 + t2);
    const double tau1 = -fx * (kL1 * s1 + kL2 * s12) + fy * (kL1 * c1 + kL2 * c12) + mz;
    const double tau2 = -fx * kL2 * s12 + fy * kL2 * c12 + mz;
    const double d1 = tau1 / kK1;
    const double d2 = tau2 / kK2;
    JointVector dtheta;
    joint_deflection(m, ws, q, w, dtheta);
    EXPECT_NEAR(dtheta[0], d1, 1e-15);
    EXPECT_NEAR(dtheta[1], d2, 1e-15);
    const Displacement dx = tcp_deflection(m, ws, q, w);
    EXPECT_NEAR(dx[0], -(kL1 * s1 + kL2 * s12) * d1 - kL2 * s12 * d2, 1e-15);
    EXPECT_NEAR(dx[1], (kL1 * c1 + kL2 * c12) * d1 + kL2 * c12 * d2, 1e-15);
    EXPECT_NEAR(dx[2], 0.0, 1e-18);
    EXPECT_NEAR(dx[5], d1 + d2, 1e-15);
    // Cartesian compliance, x-x entry: sum_j J_xj^2 / k_j.
    const Matrix6 C = cartesian_compliance(m, ws, q);
    const double jx1 = -(kL1 * s1 + kL2 * s12);
    const double jx2 = -kL2 * s12;
    EXPECT_NEAR(C(0, 0), jx1 * jx1 / kK1 + jx2 * jx2 / kK2, 1e-18);
    EXPECT_NEAR(C(5, 5), 1.0 / kK1 + 1.0 / kK2, 1e-18);
    EXPECT_LT((C - C.transpose()).norm(), 1e-20);
  }
}

TEST(Compliance, CartesianComplianceTimesWrenchIsTheDeflection) {
  const RobotModel m = test::irb6700_with_tool();
  Workspace ws(m);
  JointVector q(6);
  q << 0.2, 0.5, 0.1, -0.4, 0.9, 0.3;
  Wrench w;
  w << 300, -200, -500, 20, 10, -15;
  // With the WAP at the TCP, C W = J K^-1 J^T W = J dtheta.
  EXPECT_LT((cartesian_compliance(m, ws, q) * w - tcp_deflection(m, ws, q, w)).norm(), 1e-15);
}

TEST(Compliance, Irb6700DeflectionHasThePapersOrderOfMagnitude) {
  // Reference (shared/reference/irb6700.md): 125 N at the TCP of q = [0, 30, 10, 0, 50, 0] deg
  // deflects it by about 0.09 to 0.22 mm depending on the direction.
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0, deg_to_rad(30), deg_to_rad(10), 0, deg_to_rad(50), 0;
  double lo = 1e9;
  double hi = 0;
  for (int axis = 0; axis < 3; ++axis) {
    Wrench w = Wrench::Zero();
    w[axis] = 125.0;
    const double d = tcp_deflection(m, ws, q, w).head<3>().norm();
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  EXPECT_NEAR(lo, 0.09e-3, 0.01e-3);
  EXPECT_NEAR(hi, 0.22e-3, 0.01e-3);
}

// An IRB 6700 configuration in its working range and a wrench of up to 650 N and 30 Nm per axis.
void random_loaded_configuration(std::mt19937_64& rng, JointVector& q, Wrench& w) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  q.resize(6);
  q << 0.5 * u(rng), 0.3 + 0.3 * u(rng), 0.2 * u(rng), u(rng), 0.9 + 0.3 * u(rng), u(rng);
  w << 650 * u(rng), 650 * u(rng), 650 * u(rng), 30 * u(rng), 30 * u(rng), 30 * u(rng);
}

TEST(Compliance, CompensatedCommandDeflectsExactlyOntoTheDesiredConfiguration) {
  const RobotModel m = test::irb6700_with_tool();
  Workspace ws(m);
  std::mt19937_64 rng(3);
  for (int s = 0; s < 50; ++s) {
    JointVector q_des;
    Wrench w;
    random_loaded_configuration(rng, q_des, w);
    JointVector q_cmd;
    compensated_configuration(m, ws, q_des, w, q_cmd);
    JointVector q_actual;
    ASSERT_EQ(deflected_configuration(m, ws, q_cmd, w, q_actual), DeflectionStatus::kConverged);
    EXPECT_LT((q_actual - q_des).cwiseAbs().maxCoeff(), 1e-14);
    const Pose want = tcp_pose(m, ws, q_des);
    const Pose got = tcp_pose(m, ws, q_actual);
    EXPECT_LT((want.translation() - got.translation()).norm(), 1e-12);
  }
}

TEST(Compliance, WarmStartedDeflectionFindsTheSameFixedPointInFewerSteps) {
  const RobotModel m = test::irb6700_with_tool();
  Workspace ws(m);
  std::mt19937_64 rng(17);
  for (int s = 0; s < 50; ++s) {
    JointVector q_cmd;
    Wrench w;
    random_loaded_configuration(rng, q_cmd, w);
    JointVector cold;
    ASSERT_EQ(deflected_configuration(m, ws, q_cmd, w, cold), DeflectionStatus::kConverged);
    // The fixed point itself, checked on the equation: q = q_cmd + K^-1 J(q)^T W with J by central
    // differences of forward kinematics (not the code's Jacobian).
    const Jacobian J = test::fd_wap_jacobian(m, cold);
    const JointVector fixed = q_cmd + m.compliance().cwiseProduct(J.transpose() * w);
    EXPECT_LT((fixed - cold).cwiseAbs().maxCoeff(), 1e-9);
    // Started beside the answer, at the first step's point, or far off: the same point to 1e-13
    // rad, and a start nearer than q_cmd needs fewer iterations (the step test still decides).
    JointVector dtheta;
    joint_deflection(m, ws, q_cmd, w, dtheta);
    const JointVector first_step = q_cmd + dtheta;
    JointVector far_off = q_cmd;
    far_off.array() += 0.02;
    for (const JointVector* start : std::initializer_list<const JointVector*>{&first_step, &cold, &far_off}) {
      JointVector warm;
      ASSERT_EQ(deflected_configuration_from(m, ws, q_cmd, w, *start, warm), DeflectionStatus::kConverged);
      EXPECT_LT((warm - cold).cwiseAbs().maxCoeff(), 1e-13);
    }
    int cold_steps = 1, warm_steps = 1;
    JointVector out;
    while (deflected_configuration(m, ws, q_cmd, w, out, 1e-13, cold_steps) != DeflectionStatus::kConverged) {
      ++cold_steps;
    }
    while (deflected_configuration_from(m, ws, q_cmd, w, first_step, out, 1e-13, warm_steps) !=
           DeflectionStatus::kConverged) {
      ++warm_steps;
    }
    EXPECT_EQ(warm_steps, cold_steps - 1);
  }
}

TEST(Compliance, ComplementaryStiffnessMatchesFiniteDifferences) {
  const RobotModel m = test::irb6700_with_tool();
  Workspace ws(m);
  JointVector q(6);
  q << 0.3, 0.6, -0.2, 0.7, 1.0, -0.4;
  Wrench w;
  w << 400, -250, -600, 25, -10, 40;
  JointMatrix Kc;
  complementary_stiffness(m, ws, q, w, Kc);
  Jacobian J;
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    JointVector qp = q;
    JointVector qm = q;
    qp[k] += h;
    qm[k] -= h;
    jacobian(m, ws, qp, EndPoint::kWap, J);
    const JointVector tp = J.transpose() * w;
    jacobian(m, ws, qm, EndPoint::kWap, J);
    const JointVector tm = J.transpose() * w;
    const JointVector fd = (tp - tm) / (2 * h);
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(Kc(i, k), fd[i], 1e-5 * (1.0 + std::abs(fd[i]))) << "i=" << i << " k=" << k;
    }
  }
}

TEST(Compliance, ComplementaryStiffnessIsSmallAtThePapersLoads) {
  // At the paper's largest load (650 N) the complementary term changes the TCP deflection of the
  // IRB6700 by well under 1 %: it stays off by default, like in the paper. It must not be zero,
  // and it must move the first-order answer towards the exact fixed point.
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0, deg_to_rad(30), deg_to_rad(10), 0, deg_to_rad(50), 0;
  Wrench w;
  w << 650 * std::cos(0.6), 650 * std::sin(0.6) * 0.5, -650 * 0.8, 0, 0, 0;
  ComplianceOptions with;
  with.complementary_stiffness = true;
  JointVector d0;
  JointVector d1;
  joint_deflection(m, ws, q, w, d0);
  joint_deflection(m, ws, q, w, d1, with);
  const double rel = (d1 - d0).norm() / d0.norm();
  EXPECT_GT(rel, 1e-5);
  EXPECT_LT(rel, 1e-2);
  JointVector q_actual;
  ASSERT_EQ(deflected_configuration(m, ws, q, w, q_actual), DeflectionStatus::kConverged);
  const JointVector exact = q_actual - q;
  EXPECT_LT((exact - d1).norm(), (exact - d0).norm());
  RecordProperty("relative_change_at_650N", std::to_string(rel));
}

TEST(Compliance, HotPathsDoNotAllocate) {
  const RobotModel m = test::irb6700_with_tool();
  Workspace ws(m);
  JointVector q(6);
  q << 0.3, 0.6, -0.2, 0.7, 1.0, -0.4;
  Wrench w;
  w << 400, -250, -600, 25, -10, 40;
  JointVector dtheta(6);
  JointVector q_cmd(6);
  JointVector q_act(6);
  Jacobian J(6, 6);
  JointMatrix Kc(6, 6);
  ComplianceOptions with;
  with.complementary_stiffness = true;
  test::AllocationGuard guard;
  forward_kinematics(m, ws, q);
  jacobian(m, ws, q, EndPoint::kTcp, J);
  joint_deflection(m, ws, q, w, dtheta);
  joint_deflection(m, ws, q, w, dtheta, with);
  const Displacement dx = tcp_deflection(m, ws, q, w);
  const Matrix6 C = cartesian_compliance(m, ws, q);
  complementary_stiffness(m, ws, q, w, Kc);
  compensated_configuration(m, ws, q, w, q_cmd);
  (void)deflected_configuration(m, ws, q_cmd, w, q_act);
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_TRUE(dx.allFinite());
  EXPECT_TRUE(C.allFinite());
}

TEST(Compliance, AllocationGuardCountsAllocations) {
  // The guard itself must be able to fail, or the test above proves nothing.
  test::AllocationGuard guard;
  auto* p = new std::vector<double>(100);
  delete p;
  EXPECT_GE(guard.allocations(), 2u);
}

}  // namespace
}  // namespace deflex
