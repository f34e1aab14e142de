// Path inverse kinematics (FK round trip, configuration kept, errors naming the point, the one-arm
// shortcut against the full solve and KDL's forward kinematics) and the pose path CSV reader.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <kdl/chainfksolverpos_recursive.hpp>

#include "deflex/paths/detail/pose_path_csv.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "model/kdl_chain.hpp"
#include "support/allocation_guard.hpp"
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

/// The path IK before the one-arm shortcut: every point by inverse_kinematics() with the first
/// point's configuration and the previous joints as the seed, up to the first point where the path
/// would stop (a failure, a near-singular point or a step above the default 30 deg).
std::vector<JointVector> path_by_full_solve(const RobotModel& model, const std::vector<Pose>& poses,
                                            const IkRequest& first) {
  Workspace ws(model);
  IkRequest request = first;
  std::vector<JointVector> out;
  for (const Pose& pose : poses) {
    const IkResult r = inverse_kinematics(model, ws, pose, request);
    if (r.status != IkStatus::kOk ||
        (!out.empty() && (r.q - out.back()).cwiseAbs().maxCoeff() > PathIkOptions{}.max_joint_step_rad)) {
      break;
    }
    if (out.empty()) {
      request.configuration = r.configuration;
      request.match_quadrants = false;
    }
    out.push_back(r.q);
    request.seed = r.q;
  }
  return out;
}

// After the first point the solver solves only the arm of the path's configuration: on random walks
// in joint space (every configuration, both shoulders and elbows, singularities crossed on the way)
// it gives exactly what solving every branch gives, point for point, and its joints reproduce the
// poses through KDL's forward kinematics.
TEST(PathIk, OneArmShortcutGivesTheFullSolvesAnswerOnRandomPaths) {
  std::vector<RobotModel> robots{builtin_irb6700(),
                                 load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r2700.yaml")};
  for (const RobotModel& model : robots) {
    Workspace ws(model);
    const KDL::Chain chain = test::kdl_chain_from_dh(model);
    KDL::ChainFkSolverPos_recursive kdl_fk(chain);
    std::mt19937_64 rng(28);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::size_t compared = 0;
    for (int p = 0; p < 150; ++p) {
      JointVector q(6);
      for (int i = 0; i < 6; ++i) {
        const double lo = std::max(-3.0, model.lower_limits()[i] + 0.2);
        const double hi = std::min(3.0, model.upper_limits()[i] - 0.2);
        q[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
      }
      IkRequest first;
      first.seed = q;  // the start's own branch: any configuration
      std::vector<Pose> poses;
      for (int k = 0; k < 150; ++k) {
        poses.push_back(tcp_pose(model, ws, q));
        for (int i = 0; i < 6; ++i) {
          q[i] = std::clamp(q[i] + deg_to_rad(1.0) * unit(rng), model.lower_limits()[i], model.upper_limits()[i]);
        }
      }
      const std::vector<JointVector> want = path_by_full_solve(model, poses, first);
      PathIkSolver solver(model, first);
      for (std::size_t i = 0; i < want.size(); ++i) {
        JointVector got;
        ASSERT_NO_THROW(got = solver.next(poses[i])) << "path " << p << " point " << i;
        ASSERT_LT((got - want[i]).cwiseAbs().maxCoeff(), 1e-12) << "path " << p << " point " << i;
        KDL::JntArray k(6);
        for (unsigned j = 0; j < 6; ++j) {
          k(j) = got[static_cast<int>(j)];
        }
        KDL::Frame f;
        kdl_fk.JntToCart(k, f);
        // KDL's chain holds the base and tool frames: its end frame is the TCP in the base frame.
        double rotation_error = 0.0;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            rotation_error = std::max(rotation_error, std::abs(f.M(r, c) - poses[i].linear()(r, c)));
          }
        }
        EXPECT_LT((Vector3(f.p.x(), f.p.y(), f.p.z()) - poses[i].translation()).norm(), 1e-9)
            << "path " << p << " point " << i;
        EXPECT_LT(rotation_error, 1e-9) << "path " << p << " point " << i;
        ++compared;
      }
    }
    EXPECT_GT(compared, 10000U);
  }
}

// The one-arm shortcut, like the full solve, allocates nothing a point (offline streams millions).
TEST(PathIk, APointAfterTheFirstAllocatesNothing) {
  const RobotModel model = builtin_irb6700();
  const auto poses = sample_circle(default_circle(), kToolDown);
  PathIkSolver solver(model, IkRequest{});
  (void)solver.next(poses[0]);
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    for (std::size_t i = 1; i < poses.size(); ++i) {
      (void)solver.next(poses[i]);
    }
    allocations = guard.allocations();
  }
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(solver.points(), poses.size());
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
