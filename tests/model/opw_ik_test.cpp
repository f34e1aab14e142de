// Analytic IK for ortho-parallel arms: the parameters derived from the geometry against published
// OPW parameter sets, every solution against KDL (forward kinematics and its numerical
// Levenberg-Marquardt solver) over a seeded sweep of seven robots, ABB and KUKA configurations
// against their geometric definitions, and the hot path's allocations.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include <gtest/gtest.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "deflex/model/opw_ik.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "kdl_chain.hpp"
#include "kdl_reference_chain.hpp"
#include "support/allocation_guard.hpp"
#include "test_robots.hpp"

namespace deflex {
namespace {

std::string fixture(const std::string& name) {
  return std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/ros-industrial/" + name;
}

struct TestRobot {
  std::string label;
  RobotModel model;
  KDL::Chain chain;  // independent of deflex: from the URDF text or the DH table
};

std::vector<TestRobot> test_robots() {
  std::vector<TestRobot> out;
  const RobotModel irb = builtin_irb6700();
  out.push_back({"IRB6700 (DH)", irb, test::kdl_chain_from_dh(irb)});
  const RobotModel kr = load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r2700.yaml");
  out.push_back({"KR210 R2700 (DH, tool)", kr, test::kdl_chain_from_dh(kr)});
  for (const char* f : {"abb_irb6700_235_265.urdf", "kuka_kr120r2500pro.urdf", "kuka_kr210_r3100_2.urdf",
                        "fanuc_m10ia.urdf", "staubli_tx2_60l.urdf"}) {
    out.push_back({f, load_robot(fixture(f)),
                   test::kdl_chain_from_reference(test::reference_chain(fixture(f), "base_link", "tool0"))});
  }
  return out;
}

double wrapped(double a) { return std::remainder(a, 2.0 * kPi); }

double pose_error(const Pose& a, const Pose& b) {
  return (a.translation() - b.translation()).norm() + (a.linear() - b.linear()).norm();
}

TEST(OpwIk, DerivedParametersMatchThePublishedOpwSets) {
  // kuka_experimental, kuka_kr210_support/config/opw_parameters_kr210_r3100-2.yaml (q = (theta + offset) * sign):
  // a1 0.33, a2 -0.115, b 0, c1 0.645, c2 1.35, c3 1.42, c4 0.240, offsets [0, -90 deg, 0, 0, 0, 0],
  // signs [-1, 1, 1, -1, 1, -1].
  {
    const RobotModel m = load_robot(fixture("kuka_kr210_r3100_2.urdf"));
    ASSERT_NE(m.opw(), nullptr) << m.opw_note();
    const OpwGeometry& g = *m.opw();
    const double want[7] = {0.33, -0.115, 0.0, 0.645, 1.35, 1.42, 0.240};
    const double got[7] = {g.a1, g.a2, g.b, g.c1, g.c2, g.c3, g.c4};
    for (int i = 0; i < 7; ++i) {
      EXPECT_NEAR(got[i], want[i], 1e-12) << "parameter " << i;
    }
    const double sign[6] = {-1, 1, 1, -1, 1, -1};
    const double offset_deg[6] = {0, -90, 0, 0, 0, 0};
    for (int i = 0; i < 6; ++i) {
      EXPECT_EQ(g.sign[static_cast<std::size_t>(i)], sign[i]) << "joint " << i + 1;
      // theta = sign * q + offset here, theta = q * sign - offset_published there.
      EXPECT_NEAR(rad_to_deg(g.offset[static_cast<std::size_t>(i)]), -offset_deg[i] * sign[i], 1e-9) << i + 1;
    }
  }
  // staubli_experimental, staubli_tx2_60_support/config/opw_parameters_tx2_60l.yaml:
  // a1 0, a2 0, b 0.02, c1 0.375, c2 0.40, c3 0.45, c4 0.07, offsets 0, signs 1.
  {
    const RobotModel m = load_robot(fixture("staubli_tx2_60l.urdf"));
    ASSERT_NE(m.opw(), nullptr) << m.opw_note();
    const OpwGeometry& g = *m.opw();
    const double want[7] = {0.0, 0.0, 0.02, 0.375, 0.40, 0.45, 0.07};
    const double got[7] = {g.a1, g.a2, g.b, g.c1, g.c2, g.c3, g.c4};
    for (int i = 0; i < 7; ++i) {
      EXPECT_NEAR(got[i], want[i], 1e-12) << "parameter " << i;
    }
    for (int i = 0; i < 6; ++i) {
      EXPECT_EQ(g.sign[static_cast<std::size_t>(i)], 1.0);
      EXPECT_NEAR(g.offset[static_cast<std::size_t>(i)], 0.0, 1e-12);
    }
  }
}

TEST(OpwIk, EveryRobotOfTheSweepIsOrthoParallelAndOthersAreNot) {
  for (const TestRobot& r : test_robots()) {
    EXPECT_TRUE(has_analytic_ik(r.model)) << r.label << ": " << r.model.opw_note();
  }
  // Axis 5 tilted by 10 degrees: not a spherical wrist.
  const RobotModel tilted = load_robot_yaml_text(R"(deflex_robot: 1
units: {length: m, angle: deg}
kinematics:
  convention: standard_dh
  joints:
    - {a: 0.32, alpha: -90, d: 0.78, min: -170, max: 170}
    - {a: 1.145, alpha: 0, d: 0, offset: -90, min: -65, max: 85}
    - {a: 0.2, alpha: -90, d: 0, min: -180, max: 70}
    - {a: 0, alpha: 80, d: 1.2125, min: -300, max: 300}
    - {a: 0, alpha: -90, d: 0, min: -130, max: 130}
    - {a: 0, alpha: 0, d: 0.25, min: -360, max: 360}
)",
                                                 "tilted");
  EXPECT_FALSE(has_analytic_ik(tilted));
  EXPECT_NE(tilted.opw_note().find("perpendicular"), std::string::npos) << tilted.opw_note();
}

// The sweep: for each robot, seeded random configurations inside the limits; the target pose comes
// from KDL's FK. OPW's solutions must each reproduce the pose under KDL's FK to 1e-9, the
// configuration the pose came from must be among them, and KDL's numerical IK, started 0.1 rad away,
// must land on one of OPW's branches whenever it converges.
TEST(OpwIk, AgreesWithKdlOnEveryReachablePoseOfASeededSweep) {
  std::mt19937_64 rng(2024);
  for (const TestRobot& r : test_robots()) {
    const RobotModel& m = r.model;
    const OpwGeometry& g = *m.opw();
    KDL::ChainFkSolverPos_recursive fk(r.chain);
    KDL::ChainIkSolverPos_LMA lma(r.chain, 1e-20, 1000, 1e-18);
    KDL::ChainJntToJacSolver jac(r.chain);
    int samples = 0, kdl_converged = 0, kdl_matched = 0, original_found = 0;
    double worst_seen = 0.0;
    for (int s = 0; s < 300; ++s) {
      JointVector q(6);
      KDL::JntArray qk(6), seed(6), out(6);
      for (int i = 0; i < 6; ++i) {
        const double lo = std::max(m.lower_limits()[i], -2.0 * kPi);
        const double hi = std::min(m.upper_limits()[i], 2.0 * kPi);
        q[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
        qk(static_cast<unsigned>(i)) = q[i];
        seed(static_cast<unsigned>(i)) = q[i] + 0.1 * std::sin(3.7 * s + 1.3 * i);
      }
      KDL::Frame target_kdl;
      fk.JntToCart(qk, target_kdl);
      const Pose target = test::to_eigen(target_kdl);
      ++samples;

      OpwSolutions sols;
      opw_solutions(m, target, &q, sols);
      ASSERT_GE(sols.count, 1) << r.label << " sample " << s << " status " << to_string(sols.status);
      bool found = false;
      for (int k = 0; k < sols.count; ++k) {
        const OpwSolution& sol = sols.solution[static_cast<std::size_t>(k)];
        KDL::JntArray qs(6);
        for (int i = 0; i < 6; ++i) {
          qs(static_cast<unsigned>(i)) = sol.q[i];
        }
        KDL::Frame f;
        fk.JntToCart(qs, f);
        EXPECT_LT(pose_error(test::to_eigen(f), target), 1e-9) << r.label << " sample " << s << " branch " << k;
        JointVector qv = sol.q;
        EXPECT_TRUE(m.within_limits(qv)) << r.label << " sample " << s;
        found = found || (qv - q).cwiseAbs().maxCoeff() < 1e-6;
      }
      EXPECT_TRUE(found) << r.label << " sample " << s << ": the configuration the pose came from is missing";
      original_found += found ? 1 : 0;

      // KDL's numerical solution, compared with every branch (no joint limits: KDL knows none).
      // KDL's Levenberg-Marquardt solver stalls at a residual of about 1e-7 (KDL's rotation
      // difference rounds angles below its epsilon, 1e-6, to zero); Newton steps on KDL's FK and
      // Jacobian, with the rotation error taken exactly, polish it to rounding.
      (void)lma.CartToJnt(seed, target_kdl, out);
      KDL::Frame f;
      for (int it = 0; it < 8; ++it) {
        fk.JntToCart(out, f);
        const Pose now = test::to_eigen(f);
        const Eigen::AngleAxisd rot(target.linear() * now.linear().transpose());
        Eigen::Matrix<double, 6, 1> e;
        e << target.translation() - now.translation(), rot.angle() * rot.axis();
        KDL::Jacobian J(6);
        jac.JntToJac(out, J);
        const Eigen::Matrix<double, 6, 6> Jm = J.data;
        out.data += Jm.fullPivLu().solve(e);
      }
      fk.JntToCart(out, f);
      if (pose_error(test::to_eigen(f), target) > 1e-9) {
        continue;
      }
      ++kdl_converged;
      OpwBranches raw;
      opw_branches(g, g.opw_T_base * target * g.tcp_T_end, g.theta(3, q[3]), 1e-2, nullptr, raw);
      bool matched = false;
      double best_worst = 1e9;
      for (int k = 0; k < raw.count && !matched; ++k) {
        double worst = 0.0;
        for (int i = 0; i < 6; ++i) {
          const double qb = g.joint(i, raw.branch[static_cast<std::size_t>(k)].theta[static_cast<std::size_t>(i)]);
          worst = std::max(worst, std::abs(wrapped(out(static_cast<unsigned>(i)) - qb)));
        }
        matched = worst < 1e-9;
        best_worst = std::min(best_worst, worst);
      }
      worst_seen = std::max(worst_seen, best_worst);
      EXPECT_TRUE(matched) << r.label << " sample " << s << ": KDL's solution is not one of OPW's branches";
      kdl_matched += matched ? 1 : 0;
    }
    EXPECT_EQ(original_found, samples) << r.label;
    EXPECT_GE(kdl_converged, samples * 95 / 100) << r.label << ": KDL converged too rarely to judge";
    EXPECT_EQ(kdl_matched, kdl_converged) << r.label;
    std::printf("%s: %d poses, KDL converged on %d, each on an OPW branch (largest joint difference %.1e rad)\n",
                r.label.c_str(), samples, kdl_converged, worst_seen);
  }
}

TEST(OpwIk, TheFkCheckOfABranchDoesNotDependOnTheOtherWristsLimits) {
  // With q5 limited to [-2, 0] one wrist of most poses leaves the limits; the other must still carry
  // the orientation error the FK check measured, the same as without the limit (it reported 0 when
  // the first wrist was the one outside).
  const RobotModel m = builtin_irb6700();
  const OpwGeometry& g = *m.opw();
  JointVector lower = m.lower_limits(), upper = m.upper_limits();
  upper[4] = 0.0;
  lower[4] = -2.0;
  const JointVector all_lower = m.lower_limits(), all_upper = m.upper_limits();
  const OpwJointFit limited{lower, upper, nullptr}, free{all_lower, all_upper, nullptr};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Workspace ws(m);
  int flipped_only = 0;
  for (int s = 0; s < 400; ++s) {
    JointVector q(6);
    for (int j = 0; j < 6; ++j)
      q[j] = 0.5 * (all_lower[j] + all_upper[j]) + 0.4 * u(rng) * (all_upper[j] - all_lower[j]);
    const Pose target = tcp_pose(m, ws, q);
    const Pose canonical = g.opw_T_base * target * g.tcp_T_end;
    OpwBranches a, b;
    opw_branches(g, canonical, g.theta(3, q[3]), 1e-2, &limited, a);
    opw_branches(g, canonical, g.theta(3, q[3]), 1e-2, &free, b);
    for (int i = 0; i < a.count; ++i) {
      const OpwBranch& x = a.branch[static_cast<std::size_t>(i)];
      for (int k = 0; k < b.count; ++k) {
        const OpwBranch& y = b.branch[static_cast<std::size_t>(k)];
        if (y.branch != x.branch) continue;
        EXPECT_EQ(x.orientation_error, y.orientation_error) << "pose " << s << " branch " << int{x.branch};
        const bool partner_kept = std::any_of(a.branch.begin(), a.branch.begin() + a.count,
                                              [&](const OpwBranch& z) { return z.branch == (x.branch ^ 1); });
        if ((x.branch & 1) != 0 && !partner_kept) ++flipped_only;
      }
    }
  }
  EXPECT_GT(flipped_only, 50) << "too few poses whose only wrist inside the limits is the flipped one";
}

TEST(OpwIk, UnreachablePosesAreUnreachableForBoth) {
  for (const TestRobot& r : test_robots()) {
    Pose far = Pose::Identity();
    far.translation() = Vector3(5.0, 1.0, 1.0);
    OpwSolutions sols;
    opw_solutions(r.model, far, nullptr, sols);
    EXPECT_EQ(sols.status, IkStatus::kUnreachable) << r.label;
    EXPECT_EQ(sols.count, 0);
    KDL::ChainIkSolverPos_LMA lma(r.chain, 1e-11, 200, 1e-15);
    KDL::JntArray seed(6), out(6);
    EXPECT_LT(lma.CartToJnt(seed, test::to_kdl(far), out), 0) << r.label;
  }
}

TEST(OpwIk, TheHotPathAllocatesNothing) {
  const RobotModel m = load_robot(fixture("kuka_kr210_r3100_2.urdf"));
  Workspace ws(m);
  JointVector q(6);
  q << 0.3, -1.2, 1.1, 0.4, 0.8, -0.5;
  const Pose target = tcp_pose(m, ws, q);
  OpwSolutions sols;
  std::size_t allocations = 0;
  {
    test::AllocationGuard guard;
    for (int i = 0; i < 100; ++i) {
      opw_solutions(m, target, &q, sols);
      opw_solutions(m, target, &q, sols, 1e-2, 1U << static_cast<unsigned>(i % 4));  // one arm
    }
    opw_solutions(m, target, &q, sols);
    allocations = guard.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GE(sols.count, 1);
}

// Asking for some arms (shoulder and elbow) gives exactly those arms' solutions of the full solve.
TEST(OpwIk, ArmsGiveTheirOwnSolutionsOfTheFullSolve) {
  for (const TestRobot& r : test_robots()) {
    Workspace ws(r.model);
    std::mt19937_64 rng(11);
    for (int n = 0; n < 300; ++n) {
      JointVector q(6);
      for (int i = 0; i < 6; ++i) {
        q[i] = std::uniform_real_distribution<double>(std::max(-3.0, r.model.lower_limits()[i]),
                                                      std::min(3.0, r.model.upper_limits()[i]))(rng);
      }
      const Pose target = tcp_pose(r.model, ws, q);
      OpwSolutions all;
      opw_solutions(r.model, target, &q, all);
      for (unsigned arms = 1; arms < kOpwAllArms; ++arms) {
        OpwSolutions some;
        opw_solutions(r.model, target, &q, some, 1e-2, arms);
        int expected = 0;
        for (int k = 0; k < all.count; ++k) {
          const OpwSolution& a = all.solution[static_cast<std::size_t>(k)];
          if (((arms >> (a.branch >> 1U)) & 1U) == 0) {
            continue;
          }
          ASSERT_LT(expected, some.count) << r.label << " pose " << n << " arms " << arms;
          const OpwSolution& b = some.solution[static_cast<std::size_t>(expected++)];
          EXPECT_EQ(a.branch, b.branch) << r.label << " pose " << n << " arms " << arms;
          EXPECT_LT((a.q - b.q).cwiseAbs().maxCoeff(), 1e-12) << r.label << " pose " << n << " arms " << arms;
          EXPECT_EQ(a.configuration, b.configuration) << r.label << " pose " << n;
          EXPECT_EQ(a.singularity, b.singularity) << r.label << " pose " << n;
        }
        EXPECT_EQ(expected, some.count) << r.label << " pose " << n << " arms " << arms;
      }
    }
  }
}

// What path IK's one-arm shortcut relies on: away from the shoulder and elbow singularities, cfx
// names the arm. Bit 2 is the back shoulder; bit 1 is the second elbow, or the first when axis 2
// turns against the canonical y axis.
TEST(OpwIk, CfxNamesTheArmAwayFromTheSingularities) {
  for (const TestRobot& r : test_robots()) {
    const OpwGeometry& g = *r.model.opw();
    Workspace ws(r.model);
    std::mt19937_64 rng(12);
    int checked = 0;
    for (int n = 0; n < 300; ++n) {
      JointVector q(6);
      for (int i = 0; i < 6; ++i) {
        q[i] = std::uniform_real_distribution<double>(std::max(-3.0, r.model.lower_limits()[i]),
                                                      std::min(3.0, r.model.upper_limits()[i]))(rng);
      }
      OpwSolutions all;
      opw_solutions(r.model, tcp_pose(r.model, ws, q), &q, all);
      for (int k = 0; k < all.count; ++k) {
        const OpwSolution& s = all.solution[static_cast<std::size_t>(k)];
        if (s.singularity == Singularity::kShoulder || s.singularity == Singularity::kElbow) {
          continue;
        }
        const int shoulder = (s.branch >> 2) & 1;
        const int elbow = (s.branch >> 1) & 1;
        EXPECT_EQ((s.configuration.cfx >> 2) & 1, shoulder) << r.label << " pose " << n;
        EXPECT_EQ((s.configuration.cfx >> 1) & 1, elbow ^ (g.sign[1] < 0.0 ? 1 : 0)) << r.label << " pose " << n;
        ++checked;
      }
    }
    EXPECT_GT(checked, 300) << r.label;
  }
}

TEST(OpwIk, SeedPicksTheNearestTurnInsideTheLimits) {
  // IRB6700 joint 6 spans +-360 deg: the same pose is reached with q6 and q6 - 360 deg.
  const RobotModel m = builtin_irb6700();
  Workspace ws(m);
  JointVector q(6);
  q << 0.2, 0.3, 0.1, 0.4, 0.7, deg_to_rad(100.0);
  const Pose target = tcp_pose(m, ws, q);
  for (const double seed6_deg : {100.0, -250.0, 300.0}) {
    JointVector seed = q;
    seed[5] = deg_to_rad(seed6_deg);
    OpwSolutions sols;
    opw_solutions(m, target, &seed, sols);
    const double want = seed6_deg < -100.0 ? deg_to_rad(100.0 - 360.0) : deg_to_rad(100.0);
    bool found = false;
    for (int k = 0; k < sols.count; ++k) {
      found = found || std::abs(sols.solution[static_cast<std::size_t>(k)].q[5] - want) < 1e-9;
    }
    EXPECT_TRUE(found) << "seed q6 " << seed6_deg;
  }
}

// KUKA Status and Turn against KUKA's definitions evaluated on the published URDF geometry: bit 0
// the wrist root point at negative x in the A1 frame, bit 1 A3 >= phi with phi = atan(115/1420)
// (the A3-A4 offset over the forearm), bit 2 A5 < 0; Turn bit i: axis i+1 negative.
TEST(OpwIk, KukaStatusAndTurnFollowTheirDefinitions) {
  const RobotModel m = load_robot(fixture("kuka_kr210_r3100_2.urdf"));
  const auto to_wrist = test::reference_chain(fixture("kuka_kr210_r3100_2.urdf"), "base_link", "link_4");
  Workspace ws(m);
  JointVector home(6);
  home << 0, deg_to_rad(-90), deg_to_rad(90), 0, 0, 0;
  EXPECT_EQ(kuka_configuration(m, ws, home), (KukaConfiguration{2, 2}));
  const double phi = std::atan2(0.115, 1.42);
  std::mt19937_64 rng(7);
  int overhead = 0;
  for (int s = 0; s < 500; ++s) {
    JointVector q(6);
    std::vector<double> qv(6);
    for (int i = 0; i < 6; ++i) {
      q[i] = qv[static_cast<std::size_t>(i)] =
          std::uniform_real_distribution<double>(m.lower_limits()[i], m.upper_limits()[i])(rng);
    }
    // The wrist root point is link_4's origin (A5 sits there); A1 turns about -z.
    const Vector3 wc = test::reference_fk(to_wrist, {qv[0], qv[1], qv[2], qv[3]}).translation();
    const double x_a1 = wc.x() * std::cos(q[0]) - wc.y() * std::sin(q[0]);
    const int status = (x_a1 < 0 ? 1 : 0) | (q[2] >= phi ? 2 : 0) | (q[4] < 0 ? 4 : 0);
    int turn = 0;
    for (int i = 0; i < 6; ++i) {
      turn |= q[i] < 0 ? 1 << i : 0;
    }
    overhead += x_a1 < 0 ? 1 : 0;
    EXPECT_EQ(kuka_configuration(m, ws, q), (KukaConfiguration{status, turn})) << "sample " << s;
    // The IK, asked for that Status and Turn, returns exactly this configuration.
    IkRequest req;
    req.kuka_configuration = KukaConfiguration{status, turn};
    const IkResult r = inverse_kinematics(m, ws, tcp_pose(m, ws, q), req);
    if (r.singularity == Singularity::kNone) {
      ASSERT_TRUE(r.ok()) << r.message;
      EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-7) << "sample " << s;
      EXPECT_EQ(r.kuka, (KukaConfiguration{status, turn}));
    }
  }
  EXPECT_GT(overhead, 10);  // the sweep covers the overhead area too
}

// ABB's cfx against its geometric definition on the ROS-Industrial IRB 6700 (joint frames from the
// independent URDF reading): wrist centre behind axis 1 along link_1's x axis, behind the lower
// arm about joint 2's axis, joint 5 negative.
TEST(OpwIk, AbbConfdataFollowsItsDefinition) {
  const std::string file = fixture("abb_irb6700_235_265.urdf");
  const RobotModel m = load_robot(file);
  const auto to1 = test::reference_chain(file, "base_link", "link_1");
  const auto to2 = test::reference_chain(file, "base_link", "link_2");
  const auto to3 = test::reference_chain(file, "base_link", "link_3");
  const auto to5 = test::reference_chain(file, "base_link", "link_5");
  Workspace ws(m);
  std::mt19937_64 rng(9);
  for (int s = 0; s < 500; ++s) {
    std::vector<double> qv(6);
    JointVector q(6);
    for (int i = 0; i < 6; ++i) {
      q[i] = qv[static_cast<std::size_t>(i)] =
          std::uniform_real_distribution<double>(m.lower_limits()[i], m.upper_limits()[i])(rng);
    }
    const Pose l1 = test::reference_fk(to1, {qv[0]});
    const Pose l2 = test::reference_fk(to2, {qv[0], qv[1]});
    const Pose l3 = test::reference_fk(to3, {qv[0], qv[1], qv[2]});
    const Vector3 wc = test::reference_fk(to5, {qv[0], qv[1], qv[2], qv[3], qv[4]}).translation();
    const bool b1 = (wc - l1.translation()).dot(l1.linear().col(0)) < 0.0;
    const Vector3 lower_arm = l3.translation() - l2.translation();
    const bool b2 = l2.linear().col(1).dot(lower_arm.cross(wc - l2.translation())) < 0.0;
    const bool b3 = q[4] < 0.0;
    const ArmConfiguration c = arm_configuration(m, ws, q);
    EXPECT_EQ(c.cfx, (b1 ? 4 : 0) + (b2 ? 2 : 0) + (b3 ? 1 : 0)) << "sample " << s;
    EXPECT_EQ(c.cf1, static_cast<int>(std::floor(q[0] / (kPi / 2))));
    EXPECT_EQ(c.cf6, static_cast<int>(std::floor(q[5] / (kPi / 2))));
  }
}

TEST(OpwIk, SingularitiesOfAUrdfArmAreReported) {
  const RobotModel m = load_robot(fixture("staubli_tx2_60l.urdf"));
  Workspace ws(m);
  // Arm straight up: the wrist centre 20 mm (b) from axis 1, in the plane through it: shoulder.
  JointVector q = JointVector::Zero(6);
  q[4] = 0.5;
  IkRequest req;
  req.seed = q;
  IkResult r = inverse_kinematics(m, ws, tcp_pose(m, ws, q), req);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.singularity, Singularity::kShoulder);
  // Wrist: joint 5 at zero, arm bent.
  q << 0.3, 0.5, 1.0, 0.4, 0.0, -0.2;
  req.seed = q;
  r = inverse_kinematics(m, ws, tcp_pose(m, ws, q), req);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.singularity, Singularity::kWrist);
  EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-9);  // joints 4 and 6 kept as the seed splits them
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

// A tool that only moves the TCP and a base without a turn make the solver's frame change additions
// only; a tilted tool keeps the products. Both reproduce their poses and find the configuration.
TEST(OpwIk, TheFrameChangeIsAdditionsOnlyWhenNeitherFrameTurns) {
  Pose shifted = Pose::Identity();
  shifted.translation() = Vector3(0.02, -0.01, 0.31);
  const RobotModel plain = builtin_irb6700();
  const RobotModel tool = plain.with_tool(shifted);
  const RobotModel tilted = test::irb6700_with_tool();
  EXPECT_TRUE(plain.opw()->frames_unrotated);
  EXPECT_TRUE(tool.opw()->frames_unrotated);
  EXPECT_FALSE(tilted.opw()->frames_unrotated);
  std::mt19937_64 rng(77);
  for (const RobotModel* m : {&tool, &tilted}) {
    Workspace ws(*m);
    OpwSolutions sol;
    for (int s = 0; s < 200; ++s) {
      JointVector q(6);
      for (int i = 0; i < 6; ++i) {
        q[i] = std::uniform_real_distribution<double>(m->lower_limits()[i], m->upper_limits()[i])(rng);
      }
      const Pose target = tcp_pose(*m, ws, q);
      opw_solutions(*m, target, &q, sol);
      ASSERT_GT(sol.count, 0) << "sample " << s;
      bool found = false;
      for (int k = 0; k < sol.count; ++k) {
        const JointVector qk = sol.solution[static_cast<std::size_t>(k)].q;
        const Pose got = tcp_pose(*m, ws, qk);
        EXPECT_LT((got.translation() - target.translation()).norm(), 1e-10) << "sample " << s;
        EXPECT_LT((got.linear() - target.linear()).norm(), 1e-10) << "sample " << s;
        found = found || (qk - q).cwiseAbs().maxCoeff() < 1e-9;
      }
      EXPECT_TRUE(found) << "sample " << s;
    }
  }
}

}  // namespace
}  // namespace deflex
