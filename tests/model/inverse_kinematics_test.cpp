// Inverse kinematics round trips over the workspace, near and at singularities, out of reach, and
// for an arm without an analytic solver.
#include <random>

#include <gtest/gtest.h>

#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "test_robots.hpp"

namespace deflex {
namespace {

JointVector random_q(const RobotModel& m, std::mt19937_64& rng) {
  JointVector q(m.dof());
  for (int i = 0; i < m.dof(); ++i) {
    q[i] = std::uniform_real_distribution<double>(m.lower_limits()[i], m.upper_limits()[i])(rng);
  }
  return q;
}

double pose_error(const RobotModel& m, Workspace& ws, const JointVector& q, const Pose& target) {
  return pose_difference(tcp_pose(m, ws, q), target).norm();
}

TEST(InverseKinematics, RoundTripWithTheSameConfigurationGivesTheSameJoints) {
  for (const RobotModel& m : {builtin_irb6700(), test::irb6700_with_tool()}) {
    ASSERT_TRUE(has_analytic_ik(m));
    Workspace ws(m);
    std::mt19937_64 rng(11);
    int checked = 0;
    for (int s = 0; s < 2000; ++s) {
      const JointVector q = random_q(m, rng);
      if (std::abs(std::sin(q[4])) < 0.05) {
        continue;  // near the wrist singularity joints 4 and 6 are not unique (tested below)
      }
      const Pose target = tcp_pose(m, ws, q);
      IkRequest req;
      req.configuration = arm_configuration(m, ws, q);
      const IkResult r = inverse_kinematics(m, ws, target, req);
      ASSERT_TRUE(r.ok()) << r.message;
      EXPECT_TRUE(r.analytic);
      EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-8) << "sample " << s;
      EXPECT_LT(pose_error(m, ws, r.q, target), 1e-10);
      ++checked;
    }
    EXPECT_GT(checked, 1500);
  }
}

TEST(InverseKinematics, EverySolutionReachesTheTargetAndConfigurationsDiffer) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0.2, 0.3, 0.1, 0.4, 0.7, -0.3;
  const Pose target = tcp_pose(m, ws, q);
  const auto all = all_ik_solutions(m, ws, target);
  ASSERT_GE(all.size(), 4u);
  std::set<int> cfx;
  for (const auto& s : all) {
    EXPECT_LT(pose_error(m, ws, s.q, target), 1e-10);
    EXPECT_TRUE(m.within_limits(s.q));
    cfx.insert(s.configuration.cfx);
  }
  EXPECT_GE(cfx.size(), 4u);  // front/back x elbow x wrist flip, as far as the limits allow
}

TEST(InverseKinematics, HomePoseIsConfigurationZero) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0, deg_to_rad(30), deg_to_rad(10), 0, deg_to_rad(50), 0;
  const ArmConfiguration c = arm_configuration(m, ws, q);
  EXPECT_EQ(c, (ArmConfiguration{0, 0, 0, 0}));
  q[4] = -q[4];
  EXPECT_EQ(arm_configuration(m, ws, q).cfx, 1);  // joint 5 negative
}

TEST(InverseKinematics, NearWristSingularityIsReportedAndStillExact) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  for (const double q5 : {1e-3, 1e-6, 0.0}) {
    JointVector q(6);
    q << 0.3, 0.4, -0.1, 0.5, q5, -0.2;
    const Pose target = tcp_pose(m, ws, q);
    IkRequest req;
    req.seed = q;
    const IkResult r = inverse_kinematics(m, ws, target, req);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_EQ(r.status, IkStatus::kNearSingular);
    EXPECT_EQ(r.singularity, Singularity::kWrist);
    EXPECT_LT(pose_error(m, ws, r.q, target), 1e-9);
    // Joints 4 and 6 are not unique here, but the solution closest to the seed is the seed.
    EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-5);
  }
}

TEST(InverseKinematics, ExactlyWristSingularPoseKeepsItsBranch) {
  // Regression: at q5 = 0 exactly, acos(cos q5) lost half the digits and the FK check dropped
  // the right branch, so a far-away configuration came back as "ok".
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0, deg_to_rad(10), deg_to_rad(-10), 0, 0, 0;
  const Pose target = tcp_pose(m, ws, q);
  for (const bool with_seed : {true, false}) {
    IkRequest req;
    if (with_seed) {
      req.seed = q;
    }
    const IkResult r = inverse_kinematics(m, ws, target, req);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_EQ(r.singularity, Singularity::kWrist);
    EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-9) << "seeded: " << with_seed;
    EXPECT_LT(pose_error(m, ws, r.q, target), 1e-12);
  }
}

TEST(InverseKinematics, StretchedElbowIsReported) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  // Elbow angle beta = q3' + phi3 = 0: the forearm continues the upper arm.
  const double phi3 = std::atan2(1.2125, 0.2);
  JointVector q(6);
  q << 0.1, 0.2, -phi3 + 1e-4, 0.3, 0.6, 0.2;
  const Pose target = tcp_pose(m, ws, q);
  IkRequest req;
  req.seed = q;
  const IkResult r = inverse_kinematics(m, ws, target, req);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.singularity, Singularity::kElbow);
  EXPECT_LT(pose_error(m, ws, r.q, target), 1e-8);
}

TEST(InverseKinematics, OutOfReachAndInvalidTargetsFailClearly) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  Pose far = Pose::Identity();
  far.translation() = Vector3(4.0, 0.0, 1.0);
  IkResult r = inverse_kinematics(m, ws, far);
  EXPECT_EQ(r.status, IkStatus::kUnreachable);
  EXPECT_NE(r.message.find("reach"), std::string::npos);

  Pose nan = Pose::Identity();
  nan.translation() = Vector3(std::nan(""), 0.0, 1.0);
  r = inverse_kinematics(m, ws, nan);
  EXPECT_EQ(r.status, IkStatus::kInvalidInput);

  // Behind the robot, below the floor and close to the base: reachable only outside joint limits.
  Pose low = Pose::Identity();
  low.linear() = Eigen::AngleAxisd(kPi, Vector3::UnitY()).toRotationMatrix();
  low.translation() = Vector3(-0.3, 0.0, -1.2);
  r = inverse_kinematics(m, ws, low);
  EXPECT_LT(static_cast<int>(r.status), 0);
  EXPECT_FALSE(r.message.empty());
}

TEST(InverseKinematics, UnavailableConfigurationNamesTheAvailableOnes) {
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0, deg_to_rad(30), deg_to_rad(10), 0, deg_to_rad(50), 0;
  IkRequest req;
  req.configuration = ArmConfiguration{3, 0, 0, 0};  // joint 1 in [270, 360) deg: beyond its limit
  const IkResult r = inverse_kinematics(m, ws, tcp_pose(m, ws, q), req);
  EXPECT_EQ(r.status, IkStatus::kConfigurationUnavailable);
  EXPECT_NE(r.message.find("[0,0,0,0]"), std::string::npos) << r.message;
}

TEST(InverseKinematics, NumericalSolverForArmsWithoutAnAnalyticOne) {
  const RobotModel m = test::modified_dh_arm();
  ASSERT_FALSE(has_analytic_ik(m));
  Workspace ws(m);
  std::mt19937_64 rng(5);
  int solved = 0;
  for (int s = 0; s < 40; ++s) {
    JointVector q = random_q(m, rng);
    const Pose target = tcp_pose(m, ws, q);
    IkRequest req;
    JointVector seed = q;
    for (int i = 0; i < 6; ++i) {
      seed[i] += 0.2 * std::sin(3.0 * i + s);  // a nearby start, as along a path
    }
    req.seed = seed;
    const IkResult r = inverse_kinematics(m, ws, target, req);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_FALSE(r.analytic);
    EXPECT_LT(r.position_error_m, 1e-9);
    EXPECT_LT(r.orientation_error_rad, 1e-9);
    EXPECT_TRUE(m.within_limits(r.q));
    ++solved;
  }
  EXPECT_EQ(solved, 40);
}

}  // namespace
}  // namespace deflex
