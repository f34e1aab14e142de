// Forward kinematics and the geometric Jacobian against KDL (an independent implementation), against
// finite differences of FK, and against the reference robot's published geometry.
#include <random>

#include <gtest/gtest.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "kdl_chain.hpp"
#include "test_robots.hpp"

namespace deflex {
namespace {

JointVector random_joints(const RobotModel& m, std::mt19937_64& rng) {
  JointVector q(m.dof());
  for (int i = 0; i < m.dof(); ++i) {
    const double lo = std::max(m.lower_limits()[i], -kPi);
    const double hi = std::min(m.upper_limits()[i], kPi);
    q[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  return q;
}

void expect_fk_and_jacobian_match_kdl(const RobotModel& model, int samples) {
  KDL::Chain chain = test::kdl_chain_from_dh(model);
  ASSERT_EQ(static_cast<int>(chain.getNrOfJoints()), model.dof());
  KDL::ChainFkSolverPos_recursive kdl_fk(chain);
  KDL::ChainJntToJacSolver kdl_jac(chain);
  Workspace ws(model);
  Jacobian J;
  std::mt19937_64 rng(42);
  for (int s = 0; s < samples; ++s) {
    const JointVector q = random_joints(model, rng);
    KDL::JntArray kq(static_cast<unsigned>(model.dof()));
    for (int i = 0; i < model.dof(); ++i) {
      kq(static_cast<unsigned>(i)) = q[i];
    }
    KDL::Frame f;
    ASSERT_GE(kdl_fk.JntToCart(kq, f), 0);
    KDL::Jacobian kj(static_cast<unsigned>(model.dof()));
    ASSERT_GE(kdl_jac.JntToJac(kq, kj), 0);

    jacobian(model, ws, q, EndPoint::kTcp, J);
    const Pose& T = ws.base_T_tcp;
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(T.translation()[r], f.p(r), 1e-12);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(T.linear()(r, c), f.M(r, c), 1e-12);
      }
    }
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < model.dof(); ++c) {
        EXPECT_NEAR(J(r, c), kj(static_cast<unsigned>(r), static_cast<unsigned>(c)), 1e-12)
            << "row " << r << " col " << c;
      }
    }
  }
}

TEST(Kinematics, Irb6700MatchesKdl) { expect_fk_and_jacobian_match_kdl(builtin_irb6700(), 500); }
TEST(Kinematics, Irb6700WithToolMatchesKdl) { expect_fk_and_jacobian_match_kdl(test::irb6700_with_tool(), 300); }
TEST(Kinematics, ModifiedDhArmMatchesKdl) { expect_fk_and_jacobian_match_kdl(test::modified_dh_arm(), 300); }

TEST(Kinematics, Irb6700HomePoseIsTheDatasheetFlange) {
  // Reference: all joints zero puts the flange at (1782.5, 0, 2125) mm with ABB's tool0
  // orientation, quaternion (0.7071, 0, 0.7071, 0) (shared/reference/irb6700.md).
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  const Pose T = tcp_pose(m, ws, JointVector::Zero(6));
  EXPECT_NEAR(T.translation().x(), 1.7825, 1e-12);
  EXPECT_NEAR(T.translation().y(), 0.0, 1e-12);
  EXPECT_NEAR(T.translation().z(), 2.125, 1e-12);
  const Eigen::Quaterniond q(T.linear());
  EXPECT_NEAR(std::abs(q.w()), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(std::abs(q.y()), std::sqrt(0.5), 1e-12);
  // Positive joint 2 tilts the upper arm forward: the flange moves to +x.
  JointVector q2 = JointVector::Zero(6);
  q2[1] = deg_to_rad(10.0);
  EXPECT_GT(tcp_pose(m, ws, q2).translation().x(), 1.7825);
  // Positive joint 3 tilts the forearm down.
  JointVector q3 = JointVector::Zero(6);
  q3[2] = deg_to_rad(10.0);
  EXPECT_LT(tcp_pose(m, ws, q3).translation().z(), 2.125);
}

TEST(Kinematics, JacobianMatchesFiniteDifferencesOfFk) {
  for (const RobotModel& model : {test::irb6700_with_tool(), test::modified_dh_arm()}) {
    Workspace ws(model);
    Jacobian J;
    std::mt19937_64 rng(7);
    for (int s = 0; s < 100; ++s) {
      const JointVector q = random_joints(model, rng);
      jacobian(model, ws, q, EndPoint::kTcp, J);
      const Pose T0 = ws.base_T_tcp;
      const double h = 1e-6;
      for (int j = 0; j < model.dof(); ++j) {
        JointVector qp = q;
        JointVector qm = q;
        qp[j] += h;
        qm[j] -= h;
        const Pose Tp = tcp_pose(model, ws, qp);
        const Pose Tm = tcp_pose(model, ws, qm);
        // Central difference of position; rotation from the relative rotation Tp * Tm^-1.
        const Vector3 dp = (Tp.translation() - Tm.translation()) / (2 * h);
        const Eigen::AngleAxisd aa(Tp.linear() * Tm.linear().transpose());
        const Vector3 dw = aa.angle() * aa.axis() / (2 * h);
        EXPECT_LT((dp - J.col(j).head<3>()).norm(), 1e-7);
        EXPECT_LT((dw - J.col(j).tail<3>()).norm(), 1e-7);
      }
      (void)T0;
    }
  }
}

TEST(Kinematics, PointJacobianOfWapUsesTheWapFrame) {
  // A WAP 0.2 m beyond the TCP along the tool z: the WAP Jacobian's linear part equals the TCP's
  // plus omega x r, r from TCP to WAP.
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0, 0, 0.3);
  Pose wap = tool;
  wap.translation() = Vector3(0, 0, 0.5);
  const RobotModel m = builtin_irb6700().with_tool(tool, wap);
  Workspace ws(m);
  JointVector q(6);
  q << 0.1, 0.4, -0.2, 0.3, 0.8, -0.5;
  Jacobian Jt;
  Jacobian Jw;
  jacobian(m, ws, q, EndPoint::kTcp, Jt);
  jacobian(m, ws, q, EndPoint::kWap, Jw);
  const Vector3 r = ws.base_T_wap.translation() - ws.base_T_tcp.translation();
  EXPECT_NEAR(r.norm(), 0.2, 1e-12);
  for (int j = 0; j < 6; ++j) {
    const Vector3 expected = Jt.col(j).head<3>() + Jt.col(j).tail<3>().cross(r);
    EXPECT_LT((Jw.col(j).head<3>() - expected).norm(), 1e-12);
  }
}

TEST(Kinematics, PoseDifferenceAndApplyDisplacementAreInverse) {
  Pose a = Pose::Identity();
  a.linear() = Eigen::AngleAxisd(0.7, Vector3(1, 2, 3).normalized()).toRotationMatrix();
  a.translation() = Vector3(1, 2, 3);
  Displacement d;
  d << 1e-3, -2e-3, 5e-4, 2e-3, -1e-3, 3e-3;
  const Pose b = apply_displacement(a, d);
  EXPECT_LT((pose_difference(a, b) - d).norm(), 1e-15);
}

}  // namespace
}  // namespace deflex
