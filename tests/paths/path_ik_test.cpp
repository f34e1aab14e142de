// Path inverse kinematics (FK round trip, configuration kept, errors naming the point) and the pose
// path CSV reader.
#include <gtest/gtest.h>

#include "deflex/model/robot_io.hpp"
#include "deflex/paths/detail/pose_path_csv.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

const Eigen::Quaterniond kToolDown(0.0, 0.0, 1.0, 0.0);

using test::error_of;

TEST(PathIk, DefaultCircleRoundTripsThroughFkWithOneConfiguration) {
  const RobotModel model = builtin_irb6700();
  const auto poses = sample_circle(default_circle(), kToolDown);
  const JointPath path = solve_path_ik(model, poses, IkRequest{});
  ASSERT_EQ(path.q.size(), poses.size());
  Workspace ws(model);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Pose p = tcp_pose(model, ws, path.q[i]);
    EXPECT_NEAR((p.translation() - poses[i].translation()).norm(), 0.0, 1e-9) << i;
    EXPECT_NEAR(pose_difference(p, poses[i]).tail<3>().norm(), 0.0, 1e-9) << i;
    EXPECT_EQ(arm_configuration(model, ws, path.q[i]).cfx, path.configuration.cfx) << i;
    EXPECT_TRUE(model.within_limits(path.q[i]));
    if (i > 0) {
      // A 100 mm circle at 1.5 m reach moves no joint by more than a few degrees per 4.5 deg step.
      EXPECT_LT((path.q[i] - path.q[i - 1]).cwiseAbs().maxCoeff(), deg_to_rad(5.0)) << i;
    }
  }
  // Closed circle: the last point repeats the first, so must its joints.
  EXPECT_NEAR((path.q.back() - path.q.front()).norm(), 0.0, 1e-9);
}

TEST(PathIk, RequestedConfigurationIsKept) {
  const RobotModel model = builtin_irb6700();
  const auto poses = sample_circle(default_circle(), kToolDown);
  Workspace ws(model);
  // Every configuration the first point allows; each must be kept along the whole circle.
  const auto all = all_ik_solutions(model, ws, poses[0]);
  ASSERT_GE(all.size(), 2u);
  int tried = 0;
  for (const IkResult& s : all) {
    IkRequest first;
    first.configuration = s.configuration;
    try {
      const JointPath path = solve_path_ik(model, poses, first);
      ++tried;
      EXPECT_EQ(path.configuration, s.configuration);
      for (const JointVector& q : path.q) {
        EXPECT_EQ(arm_configuration(model, ws, q).cfx, s.configuration.cfx);
      }
    } catch (const InputError&) {
      // Some branches cannot follow the whole circle (limits, singular): allowed, not every one.
    }
  }
  EXPECT_GE(tried, 1);
}

TEST(PathIk, UnreachablePointIsNamed) {
  const RobotModel model = builtin_irb6700();
  auto poses = sample_circle(default_circle(), kToolDown);
  poses[7].translation() = Vector3(4.0, 0.0, 1.0);  // beyond the 2.7 m reach
  const std::string m = error_of([&] { (void)solve_path_ik(model, poses, IkRequest{}); });
  EXPECT_NE(m.find("path point 7: unreachable"), std::string::npos) << m;
}

TEST(PathIk, SingularPointIsNamed) {
  const RobotModel model = builtin_irb6700();
  Workspace ws(model);
  // Joint 5 at 0.3 deg: near the wrist singularity (|sin q5| = 0.005 < 0.01). Its FK pose as the
  // third point of a short path. (At exactly 0 the core IK drops this branch.)
  JointVector q(6);
  q << 0.0, deg_to_rad(10.0), deg_to_rad(-10.0), 0.0, deg_to_rad(0.3), 0.0;
  const Pose singular = tcp_pose(model, ws, q);
  q[4] = deg_to_rad(20.0);
  const Pose fine = tcp_pose(model, ws, q);
  const std::vector<Pose> poses{fine, fine, singular};
  IkRequest first;
  first.seed = q;  // the branch of q itself, so the singular point is on the same branch
  const std::string m = error_of([&] { (void)solve_path_ik(model, poses, first); });
  EXPECT_NE(m.find("path point 2: singular"), std::string::npos) << m;
}

TEST(PathIk, JointJumpIsNamed) {
  const RobotModel model = builtin_irb6700();
  Workspace ws(model);
  JointVector q(6);
  q << 0.0, 0.2, 0.1, 0.0, 0.8, 0.0;
  const Pose a = tcp_pose(model, ws, q);
  q[0] = deg_to_rad(60.0);  // joint 1 swings 60 deg between neighbours
  const Pose b = tcp_pose(model, ws, q);
  const std::string m = error_of([&] { (void)solve_path_ik(model, {a, b}, IkRequest{}); });
  EXPECT_NE(m.find("path point 1: joint 1 moves"), std::string::npos) << m;
  PathIkOptions relaxed;
  relaxed.max_joint_step_rad = deg_to_rad(90.0);
  EXPECT_EQ(solve_path_ik(model, {a, b}, IkRequest{}, relaxed).q.size(), 2u);
  EXPECT_THROW((void)solve_path_ik(model, {}, IkRequest{}), InputError);
}

TEST(PosePathCsv, ReadsMillimetresAndQuaternions) {
  const auto poses = parse_pose_path_csv(
      "# a path\nqw,qx,qy,qz,x_mm,y_mm,z_mm\n0,0,1,0,1500,0,1000\n0.7071068,0,0.7071068,0,1600,-50,900\n", "p.csv");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_NEAR((poses[1].translation() - Vector3(1.6, -0.05, 0.9)).norm(), 0.0, 1e-15);
  // qw = qy = 1/sqrt2: 90 deg about y, so base x maps to -z.
  EXPECT_NEAR((poses[1].linear() * Vector3::UnitX() - Vector3(0, 0, -1)).norm(), 0.0, 1e-6);
}

TEST(PosePathCsv, ErrorsNameFileLineAndColumn) {
  EXPECT_NE(error_of([] {
              (void)parse_pose_path_csv("x_mm,y_mm,z_mm,qw,qx,qy,qz\n1,2,3,1,0,0,0\n4,5,6,0.5,0,0,0\n", "bad.csv");
            }).find("bad.csv:3: column 'qw'"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_pose_path_csv("x_mm,y_mm,z_mm,qw,qx,qy,qz\n1,2,x,1,0,0,0\n", "bad.csv");
            }).find("bad.csv:2"),
            std::string::npos);
  EXPECT_NE(
      error_of([] { (void)parse_pose_path_csv("x,y_mm,z_mm,qw,qx,qy,qz\n1,2,3,1,0,0,0\n", "bad.csv"); }).find("x_mm"),
      std::string::npos);
  EXPECT_THROW((void)parse_pose_path_csv("x_mm,y_mm,z_mm,qw,qx,qy,qz\n", "empty.csv"), DataError);
  EXPECT_THROW((void)read_pose_path_csv("/nonexistent/path.csv"), Error);
}

}  // namespace
}  // namespace deflex
