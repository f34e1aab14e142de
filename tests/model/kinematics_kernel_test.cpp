// The folded forward-kinematics kernel (model/folded_chain.hpp, detail/joint_sincos.hpp) on every robot
// deflex ships (the built-in DH arm, the DH examples, the ROS-Industrial URDFs) and on chains built to
// reach each of its paths (joint axes off z, general fixed rotations, a WAP off the TCP): the poses
// and Jacobians against Orocos KDL built from the robot's joints one by one (KDL's own frame products,
// no folding), the Jacobians against central differences of FK, and the sin/cos pass against the C
// library.
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "deflex/model/detail/joint_sincos.hpp"
#include "deflex/model/folded_chain.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "online/fd_jacobian.hpp"
#include "test_robots.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;

KDL::Frame frame_to_kdl(const Pose& p) {
  const Matrix3 r = p.linear();
  return {KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
          KDL::Vector(p.translation().x(), p.translation().y(), p.translation().z())};
}

// KDL chain from the description's joints as written (fixed transform, then a turn about the
// joint's own axis by q + offset), ending at `flange_T_end`.
KDL::Chain kdl_chain_of_joints(const RobotModel& m, const Pose& flange_T_end) {
  const RobotDescription& d = m.description();
  KDL::Chain chain;
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame_to_kdl(d.base_T_chain)));
  for (const JointSpec& j : d.joints) {
    // The offset as a fixed turn about the same axis before the joint's own (turns about one axis commute).
    const KDL::Vector axis(j.axis.x(), j.axis.y(), j.axis.z());
    chain.addSegment(
        KDL::Segment(KDL::Joint(KDL::Joint::None),
                     frame_to_kdl(j.parent_T_joint) * KDL::Frame(KDL::Rotation::Rot2(axis, j.offset_rad))));
    chain.addSegment(
        KDL::Segment(KDL::Joint(j.name, KDL::Vector::Zero(), axis, KDL::Joint::RotAxis), KDL::Frame::Identity()));
  }
  chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame_to_kdl(d.last_T_flange * flange_T_end)));
  return chain;
}

std::vector<std::pair<std::string, RobotModel>> every_shipped_robot() {
  std::vector<std::pair<std::string, RobotModel>> out;
  out.emplace_back("built-in IRB 6700", builtin_irb6700());
  const fs::path examples = fs::path(DEFLEX_SOURCE_DIR) / "examples" / "robots";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(examples)) {
    if (e.path().extension() == ".yaml") files.push_back(e.path());
  }
  for (const auto& e : fs::directory_iterator(examples / "ros-industrial")) {
    if (e.path().extension() == ".urdf") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) out.emplace_back(f.filename().string(), load_robot(f.string()));
  return out;
}

// A 6R chain whose joints turn about axes off z (x, -y, a tilted one) between general rotations,
// with a tool and a WAP that both turn: every path of the kernel (permutation, general, about x).
RobotModel folded_paths_arm() {
  RobotDescription d;
  d.name = "folding test arm";
  const std::vector<Vector3> axes{Vector3::UnitZ(),       Vector3::UnitX(), -Vector3::UnitY(),
                                  Vector3(1, 2, 2) / 3.0, Vector3::UnitY(), -Vector3::UnitZ()};
  const std::vector<Vector3> rpy{{0, 0, 0}, {0.3, -0.2, 0.1},         {kPi / 2, 0, 0},
                                 {0, 0, 0}, {0.0, kPi / 2, -kPi / 2}, {-0.4, 0.7, 0.2}};
  for (std::size_t i = 0; i < axes.size(); ++i) {
    JointSpec j;
    j.name = "j" + std::to_string(i + 1);
    j.axis = axes[i];
    j.offset_rad = 0.1 * static_cast<double>(i) - 0.2;
    j.parent_T_joint.linear() =
        (Eigen::AngleAxisd(rpy[i].z(), Vector3::UnitZ()) * Eigen::AngleAxisd(rpy[i].y(), Vector3::UnitY()) *
         Eigen::AngleAxisd(rpy[i].x(), Vector3::UnitX()))
            .toRotationMatrix();
    j.parent_T_joint.translation() = Vector3(0.1 * static_cast<double>(i), 0.05, i == 0 ? 0.4 : 0.3);
    d.joints.push_back(j);
  }
  d.last_T_flange.translation() = Vector3(0, 0, 0.1);
  d.last_T_flange.linear() = Eigen::AngleAxisd(0.3, Vector3(0, 1, 1).normalized()).toRotationMatrix();
  d.base_T_chain.translation() = Vector3(0.2, -0.1, 0.05);
  d.base_T_chain.linear() = Eigen::AngleAxisd(0.4, Vector3::UnitZ()).toRotationMatrix();
  d.flange_T_tcp.translation() = Vector3(0.02, 0.0, 0.25);
  d.flange_T_tcp.linear() = Eigen::AngleAxisd(deg_to_rad(30.0), Vector3::UnitY()).toRotationMatrix();
  Pose wap = Pose::Identity();
  wap.translation() = Vector3(0.0, 0.03, 0.4);
  wap.linear() = Eigen::AngleAxisd(deg_to_rad(-20.0), Vector3::UnitX()).toRotationMatrix();
  d.flange_T_wap = wap;
  d.stiffness_nm_per_rad = {1e6, 1e6, 1e6, 2e5, 2e5, 2e5};
  return RobotModel(d);
}

JointVector random_inside_limits(const RobotModel& m, std::mt19937_64& rng) {
  JointVector q(m.dof());
  for (int i = 0; i < m.dof(); ++i) {
    q[i] = std::uniform_real_distribution<double>(m.lower_limits()[i], m.upper_limits()[i])(rng);
  }
  return q;
}

void expect_matches_kdl(const std::string& name, const RobotModel& m, EndPoint point, const Pose& flange_T_end) {
  const KDL::Chain chain = kdl_chain_of_joints(m, flange_T_end);
  KDL::ChainFkSolverPos_recursive kdl_fk(chain);
  KDL::ChainJntToJacSolver kdl_jac(chain);
  Workspace ws(m);
  Jacobian J;
  std::mt19937_64 rng(2026);
  for (int s = 0; s < 300; ++s) {
    const JointVector q = random_inside_limits(m, rng);
    KDL::JntArray kq(static_cast<unsigned>(m.dof()));
    for (int i = 0; i < m.dof(); ++i) kq(static_cast<unsigned>(i)) = q[i];
    KDL::Frame f;
    ASSERT_GE(kdl_fk.JntToCart(kq, f), 0);
    KDL::Jacobian kj(static_cast<unsigned>(m.dof()));
    ASSERT_GE(kdl_jac.JntToJac(kq, kj), 0);
    jacobian(m, ws, q, point, J);
    const Pose& T = end_pose(ws, point);
    for (int r = 0; r < 3; ++r) {
      ASSERT_NEAR(T.translation()[r], f.p(r), 1e-12) << name << " sample " << s;
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(T.linear()(r, c), f.M(r, c), 1e-12) << name << " sample " << s;
    }
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < m.dof(); ++c) {
        ASSERT_NEAR(J(r, c), kj(static_cast<unsigned>(r), static_cast<unsigned>(c)), 1e-12)
            << name << " sample " << s << " row " << r << " col " << c;
      }
    }
  }
}

TEST(KinematicsKernel, EveryShippedRobotMatchesKdlJointByJoint) {
  const auto robots = every_shipped_robot();
  ASSERT_GE(robots.size(), 8U);  // the built-in arm, 2 DH examples, 5 URDFs
  for (const auto& [name, m] : robots) {
    expect_matches_kdl(name, m, EndPoint::kTcp, m.description().flange_T_tcp);
    expect_matches_kdl(name, m, EndPoint::kFlange, Pose::Identity());
  }
}

TEST(KinematicsKernel, AxesOffZAndGeneralRotationsMatchKdl) {
  const RobotModel m = folded_paths_arm();
  expect_matches_kdl("folding test arm", m, EndPoint::kTcp, m.description().flange_T_tcp);
  expect_matches_kdl("folding test arm", m, EndPoint::kWap, *m.description().flange_T_wap);
  // The test arm reaches every kind of fixed step the kernel has.
  const FoldedChain& c = m.folded_chain();
  std::vector<FoldedStep::Turn> kinds;
  for (int i = 1; i < c.dof; ++i) kinds.push_back(c.steps[static_cast<std::size_t>(i)].turn);
  kinds.push_back(c.last_to_flange.turn);
  kinds.push_back(c.flange_to_tcp.turn);
  kinds.push_back(c.flange_to_wap.turn);
  for (const auto kind : {FoldedStep::Turn::kPermutation, FoldedStep::Turn::kGeneral}) {
    EXPECT_NE(std::find(kinds.begin(), kinds.end(), kind), kinds.end()) << static_cast<int>(kind);
  }
}

TEST(KinematicsKernel, JacobiansMatchCentralDifferencesOfFkOnEveryShippedRobot) {
  auto robots = every_shipped_robot();
  robots.emplace_back("folding test arm", folded_paths_arm());
  for (const auto& [name, m] : robots) {
    Workspace ws(m);
    Jacobian J;
    std::mt19937_64 rng(5);
    for (int s = 0; s < 50; ++s) {
      const JointVector q = random_inside_limits(m, rng);
      jacobian(m, ws, q, EndPoint::kWap, J);
      const Jacobian fd = test::fd_wap_jacobian(m, q);
      for (int j = 0; j < m.dof(); ++j) {
        EXPECT_LT((fd.col(j).head<3>() - J.col(j).head<3>()).norm(), 1e-7) << name << " joint " << j + 1;
        EXPECT_LT((fd.col(j).tail<3>() - J.col(j).tail<3>()).norm(), 1e-7) << name << " joint " << j + 1;
      }
    }
  }
}

TEST(KinematicsKernel, DhTwistsFoldToQuarterTurnsAndTurnsAboutX) {
  // The built-in arm's twists are 0 and +-90 degrees: the identity, or a quarter turn about x whose
  // sign is the twist's.
  const RobotModel& arm = builtin_irb6700();
  const FoldedChain& c = arm.folded_chain();
  for (int i = 1; i < c.dof; ++i) {
    const FoldedStep& step = c.steps[static_cast<std::size_t>(i)];
    const double twist = arm.description().joints[static_cast<std::size_t>(i)].parent_T_joint.linear()(2, 1);
    if (std::abs(twist) < 0.5) {
      EXPECT_EQ(step.turn, FoldedStep::Turn::kIdentity) << i;
    } else {
      EXPECT_EQ(step.turn, FoldedStep::Turn::kQuarterX) << i;
      EXPECT_EQ(step.s, twist > 0.0 ? 1.0 : -1.0) << i;
    }
  }
  // Rx(90): y' = z, z' = -y, as the rotation's own columns say.
  Pose quarter = Pose::Identity();
  quarter.linear() << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  EXPECT_EQ(fold_step(quarter).turn, FoldedStep::Turn::kQuarterX);
  EXPECT_EQ(fold_step(quarter).s, 1.0);
  // A permutation that is not a turn about x stays a general permutation.
  Pose swap_xy = Pose::Identity();
  swap_xy.linear() << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  EXPECT_EQ(fold_step(swap_xy).turn, FoldedStep::Turn::kPermutation);
  // A twist off 90 degrees (a calibrated arm's) is a turn about x with its own cos and sin.
  Pose twisted = Pose::Identity();
  twisted.linear() = Eigen::AngleAxisd(deg_to_rad(-89.99), Vector3::UnitX()).toRotationMatrix();
  twisted.translation() = Vector3(0.32, 0.0, 0.0);
  const FoldedStep step = fold_step(twisted);
  EXPECT_EQ(step.turn, FoldedStep::Turn::kAboutX);
  EXPECT_DOUBLE_EQ(step.c, std::cos(deg_to_rad(-89.99)));
  EXPECT_DOUBLE_EQ(step.s, std::sin(deg_to_rad(-89.99)));
  EXPECT_EQ(step.translation_mask, 1U);
}

// The sin/cos pass against the C library: within 2 ulp, next to the zeros too (the four-part reduction
// keeps the reduced angle's error far below an ulp of the result there).
::testing::AssertionResult sincos_close_to_library(double got, double want, double x) {
  const double ulp = std::nextafter(std::abs(want), HUGE_VAL) - std::abs(want);
  if (std::abs(got - want) <= 2.0 * ulp) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "x = " << x << ": " << got << " vs " << want << " ("
                                       << std::abs(got - want) / ulp << " ulp)";
}

TEST(KinematicsKernel, JointSinCosIsTheLibrarysWithinTwoUlp) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> wide(-60.0, 60.0);
  std::uniform_real_distribution<double> tiny(-1e-9, 1e-9);
  std::array<double, kMaxJoints> a{}, c{}, s{};
  for (int t = 0; t < 200000; ++t) {
    for (int i = 0; i < kMaxJoints; ++i) {
      const auto k = static_cast<std::size_t>(i);
      switch ((t + i) % 3) {
        case 0:
          a[k] = wide(rng);
          break;
        case 1:  // next to a quadrant's edge, where the reduction and the quadrant switch meet
          a[k] = std::round(wide(rng)) * kPi / 4 + tiny(rng);
          break;
        default:
          a[k] = 1e-3 * wide(rng);
          break;
      }
    }
    detail::joint_sincos(a, kMaxJoints, c, s);
    for (std::size_t k = 0; k < a.size(); ++k) {
      ASSERT_TRUE(sincos_close_to_library(c[k], std::cos(a[k]), a[k]));
      ASSERT_TRUE(sincos_close_to_library(s[k], std::sin(a[k]), a[k]));
    }
  }
  // Exactly on the quadrant edges and zero; beyond the reduced range the library answers.
  const std::array<double, kMaxJoints> edges{0.0, kPi / 2, -kPi / 2, kPi, -kPi, 2 * kPi, 3e7};
  detail::joint_sincos(edges, kMaxJoints, c, s);
  for (std::size_t k = 0; k < edges.size(); ++k) {
    EXPECT_TRUE(sincos_close_to_library(c[k], std::cos(edges[k]), edges[k]));
    EXPECT_TRUE(sincos_close_to_library(s[k], std::sin(edges[k]), edges[k]));
  }
  EXPECT_EQ(c[6], std::cos(3e7));
  EXPECT_EQ(s[6], std::sin(3e7));
}

}  // namespace
}  // namespace deflex
