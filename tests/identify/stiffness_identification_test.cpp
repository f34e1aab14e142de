// Tests of identify_stiffness() on data made by paths independent of its regressor: Orocos KDL's
// Jacobian (exact first-order data) and the core's deflected_configuration() + FK (the nonlinear
// deflection the arm really takes), with Gaussian noise and injected outliers.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <kdl/chainjnttojacsolver.hpp>

#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "model/kdl_chain.hpp"
#include "model/test_robots.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

RobotModel kr210_model() {
  return load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r2700.yaml");
}

// A random configuration inside the limits (wrist joints within +-150 deg) and away from
// singularities, so every joint moves the TCP.
JointVector random_configuration(const RobotModel& model, std::mt19937& rng) {
  Workspace ws(model);
  for (;;) {
    JointVector q(model.dof());
    for (int j = 0; j < model.dof(); ++j) {
      const double lo = std::max(model.lower_limits()[j], -2.6);
      const double hi = std::min(model.upper_limits()[j], 2.6);
      q[j] = std::uniform_real_distribution<double>(lo, hi)(rng);
    }
    if (jacobian_min_singular_value(model, ws, q) > 0.05) {
      return q;
    }
  }
}

// Force of 300..1500 N in a random direction; a moment up to 150 Nm per axis when `moments`.
Wrench random_wrench(std::mt19937& rng, bool moments) {
  std::normal_distribution<double> n01;
  Vector3 dir(n01(rng), n01(rng), n01(rng));
  dir.normalize();
  Wrench w;
  w.head<3>() = dir * std::uniform_real_distribution<double>(300.0, 1500.0)(rng);
  w.tail<3>().setZero();
  if (moments) {
    for (int k = 3; k < 6; ++k) {
      w[k] = std::uniform_real_distribution<double>(-150.0, 150.0)(rng);
    }
  }
  return w;
}

// Exact first-order measurements from KDL's Jacobian at the TCP (the WAP is the TCP here):
// dtheta = K^-1 J^T W, dp = J_lin dtheta, drot = J_ang dtheta.
std::vector<StiffnessMeasurement> kdl_linear_data(const RobotModel& model, const JointVector& k_true, int count,
                                                  bool moments, bool orientation, unsigned seed) {
  const KDL::Chain chain = test::kdl_chain_from_dh(model);
  KDL::ChainJntToJacSolver solver(chain);
  std::mt19937 rng(seed);
  std::vector<StiffnessMeasurement> data;
  for (int i = 0; i < count; ++i) {
    StiffnessMeasurement m;
    m.q = random_configuration(model, rng);
    m.wrench_base = random_wrench(rng, moments);
    KDL::JntArray qk(static_cast<unsigned>(model.dof()));
    for (int j = 0; j < model.dof(); ++j) {
      qk(static_cast<unsigned>(j)) = m.q[j];
    }
    KDL::Jacobian jk(static_cast<unsigned>(model.dof()));
    EXPECT_GE(solver.JntToJac(qk, jk), 0);
    const Eigen::MatrixXd J = jk.data;
    const Eigen::VectorXd dtheta = (J.transpose() * m.wrench_base).cwiseQuotient(Eigen::VectorXd(k_true));
    const Eigen::VectorXd dx = J * dtheta;
    m.dp_m = dx.head<3>();
    if (orientation) {
      m.drot_rad = dx.tail<3>();
    }
    data.push_back(m);
  }
  return data;
}

// Nonlinear measurements: the arm commanded to q deflects to q_actual = q + K^-1 J(q_actual)^T W
// (the core's fixed point), the tracker sees FK(q_actual) - FK(q) plus Gaussian noise.
std::vector<StiffnessMeasurement> deflected_data(const RobotModel& truth, int count, double noise_m, unsigned seed,
                                                 bool moments = true) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  Workspace ws(truth);
  std::vector<StiffnessMeasurement> data;
  for (int i = 0; i < count; ++i) {
    StiffnessMeasurement m;
    m.q = random_configuration(truth, rng);
    m.wrench_base = random_wrench(rng, moments);
    const Vector3 p0 = tcp_pose(truth, ws, m.q).translation();
    JointVector q_actual;
    EXPECT_EQ(deflected_configuration(truth, ws, m.q, m.wrench_base, q_actual), DeflectionStatus::kConverged);
    const Vector3 p1 = tcp_pose(truth, ws, q_actual).translation();
    m.dp_m = p1 - p0 + Vector3(noise(rng), noise(rng), noise(rng));
    data.push_back(m);
  }
  return data;
}

// The modified-DH test arm with its TCP moved off axis 6, so position data can see joint 6.
RobotModel modified_dh_arm_off_axis_tool() {
  Pose tool = test::modified_dh_arm().description().flange_T_tcp;
  tool.translation().x() += 0.08;
  return test::modified_dh_arm().with_tool(tool);
}

TEST(IdentifyStiffness, NoiseFreeDataRecoverTheStiffnessTo1e9) {
  for (const RobotModel& model : {kr210_model(), modified_dh_arm_off_axis_tool()}) {
    const JointVector k_true = model.stiffness();
    for (bool orientation : {false, true}) {
      const auto data = kdl_linear_data(model, k_true, 60, true, orientation, 7);
      const StiffnessEstimate est = identify_stiffness(model, data);
      ASSERT_EQ(est.stiffness_nm_per_rad.size(), 6u);
      for (int j = 0; j < 6; ++j) {
        EXPECT_NEAR(est.stiffness_nm_per_rad[static_cast<std::size_t>(j)] / k_true[j], 1.0, 1e-9)
            << model.name() << " joint " << j + 1 << " orientation " << orientation;
      }
      EXPECT_TRUE(est.unidentifiable_joints.empty());
      EXPECT_TRUE(est.rejected_measurements.empty());
      EXPECT_LT(est.residual_rms_m, 1e-12);
      EXPECT_GE(est.condition_number, 1.0);
      EXPECT_LT(est.condition_number, 1e3);
    }
  }
}

TEST(IdentifyStiffness, NoisyDataRecoverWithinTheReportedStandardErrors) {
  // The KUKA-class arm with a WAP that is not the TCP (a load applied 100 mm beyond the reflector):
  // the generator handles that through the core's WAP Jacobian, the identification through its own.
  Pose wap = Pose::Identity();
  wap.translation() = Vector3(0.06, 0.0, 0.35);
  const RobotModel truth = kr210_model().with_tool(kr210_model().description().flange_T_tcp, wap);
  const JointVector k_true = truth.stiffness();
  const double noise = 10e-6;
  double sum_z2 = 0.0;
  int count = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const auto data = deflected_data(truth, 150, noise, seed);
    const StiffnessEstimate est = identify_stiffness(truth, data);
    EXPECT_TRUE(est.unidentifiable_joints.empty()) << "seed " << seed;
    EXPECT_NEAR(est.sigma_m, noise, 0.25 * noise) << "seed " << seed;
    for (int j = 0; j < 6; ++j) {
      const auto ju = static_cast<std::size_t>(j);
      const double z = (est.stiffness_nm_per_rad[ju] - k_true[j]) / est.std_error_nm_per_rad[ju];
      EXPECT_LT(std::abs(z), 4.5) << "seed " << seed << " joint " << j + 1;
      EXPECT_LT(est.std_error_nm_per_rad[ju] / k_true[j], 0.2);
      sum_z2 += z * z;
      ++count;
    }
  }
  // If the standard errors are right, the normalised errors have unit variance (72 samples: the
  // RMS lies within 0.7..1.35 with a probability far above 99.9%).
  const double rms_z = std::sqrt(sum_z2 / count);
  EXPECT_GT(rms_z, 0.7);
  EXPECT_LT(rms_z, 1.35);
}

TEST(IdentifyStiffness, TukeyReweightingRejectsInjectedOutliers) {
  const RobotModel truth = kr210_model();
  const JointVector k_true = truth.stiffness();
  auto data = deflected_data(truth, 200, 10e-6, 42);
  // Ten gross errors (a reflector lost and re-seated, a wrong load): 0.3..2 mm added to one axis.
  std::mt19937 rng(3);
  std::vector<int> bad;
  for (int i = 5; i < 200; i += 20) {
    const double e = std::uniform_real_distribution<double>(0.3e-3, 2e-3)(rng) * (i % 40 == 5 ? 1.0 : -1.0);
    data[static_cast<std::size_t>(i)].dp_m[i % 3] += e;
    bad.push_back(i);
  }
  const StiffnessEstimate robust = identify_stiffness(truth, data);
  EXPECT_EQ(robust.rejected_measurements, bad);
  for (int j = 0; j < 6; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    EXPECT_LT(std::abs(robust.stiffness_nm_per_rad[ju] - k_true[j]), 4.5 * robust.std_error_nm_per_rad[ju])
        << "joint " << j + 1;
  }
  EXPECT_NEAR(robust.sigma_m, 10e-6, 3e-6);
  EXPECT_LT(robust.residual_rms_m, 15e-6);

  IdentificationOptions plain;
  plain.robust = false;
  const StiffnessEstimate ls = identify_stiffness(truth, data, plain);
  EXPECT_TRUE(ls.rejected_measurements.empty());
  double worst = 0.0;
  for (int j = 0; j < 6; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    worst = std::max(worst, std::abs(ls.stiffness_nm_per_rad[ju] - k_true[j]) / robust.std_error_nm_per_rad[ju]);
  }
  EXPECT_GT(worst, 10.0) << "plain least squares should be pulled off by the outliers";
  EXPECT_GT(ls.residual_rms_m, 5.0 * robust.residual_rms_m);
}

TEST(IdentifyStiffness, JointNeverTurnedByTheLoadsIsFlaggedNotGivenANumber) {
  // The IRB6700 without a tool: the TCP lies on axis 6, so pure forces never load joint 6.
  const RobotModel model = builtin_irb6700();
  const JointVector k_true = model.stiffness();
  const auto data = kdl_linear_data(model, k_true, 50, false, false, 11);
  const StiffnessEstimate est = identify_stiffness(model, data);
  EXPECT_EQ(est.unidentifiable_joints, std::vector<int>{6});
  EXPECT_TRUE(std::isnan(est.stiffness_nm_per_rad[5]));
  EXPECT_TRUE(std::isnan(est.std_error_nm_per_rad[5]));
  bool named = false;
  for (const auto& w : est.warnings) {
    named = named || (w.find("joint 6") != std::string::npos && w.find("not excited") != std::string::npos);
  }
  EXPECT_TRUE(named);
  for (int j = 0; j < 5; ++j) {
    EXPECT_NEAR(est.stiffness_nm_per_rad[static_cast<std::size_t>(j)] / k_true[j], 1.0, 1e-9) << "joint " << j + 1;
  }

  // With moments joint 6 is loaded, but a TCP on its axis never moves when it turns: position-only
  // data still cannot see it; orientation data can.
  const RobotModel arm = test::modified_dh_arm();
  const auto with_moments = kdl_linear_data(arm, arm.stiffness(), 50, true, false, 12);
  EXPECT_EQ(identify_stiffness(arm, with_moments).unidentifiable_joints, std::vector<int>{6});
  const auto with_rotation = kdl_linear_data(arm, arm.stiffness(), 50, true, true, 12);
  const StiffnessEstimate est6 = identify_stiffness(arm, with_rotation);
  EXPECT_TRUE(est6.unidentifiable_joints.empty());
  EXPECT_NEAR(est6.stiffness_nm_per_rad[5] / arm.stiffness()[5], 1.0, 1e-9);
}

TEST(IdentifyStiffness, OneConfigurationAndOneLoadDirectionLeaveJointsCollinear) {
  const RobotModel model = kr210_model();
  auto data = kdl_linear_data(model, model.stiffness(), 1, true, false, 5);
  const StiffnessMeasurement first = data.front();
  for (int i = 1; i < 10; ++i) {
    StiffnessMeasurement m = first;
    m.wrench_base *= 1.0 + 0.1 * i;
    m.dp_m *= 1.0 + 0.1 * i;
    data.push_back(m);
  }
  const StiffnessEstimate est = identify_stiffness(model, data);
  // Ten scaled copies of one 3-row block: rank 3, so at least three of six joints are not identified.
  EXPECT_GE(est.unidentifiable_joints.size(), 3u);
  for (int j = 0; j < 6; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    const bool flagged = std::find(est.unidentifiable_joints.begin(), est.unidentifiable_joints.end(), j + 1) !=
                         est.unidentifiable_joints.end();
    EXPECT_EQ(flagged, std::isnan(est.stiffness_nm_per_rad[ju])) << "joint " << j + 1;
    if (!flagged) {  // the others were held at the file's (here the true) values
      EXPECT_NEAR(est.stiffness_nm_per_rad[ju] / model.stiffness()[j], 1.0, 1e-6) << "joint " << j + 1;
    }
  }
  bool collinear = false;
  for (const auto& w : est.warnings) {
    collinear = collinear || w.find("collinear") != std::string::npos;
  }
  EXPECT_TRUE(collinear);
}

TEST(IdentifyStiffness, FixedJointsAreHeldAndTheRestRecovered) {
  const RobotModel model = kr210_model();
  const JointVector k_true = model.stiffness();
  const auto data = kdl_linear_data(model, k_true, 40, true, false, 9);
  IdentificationOptions opt;
  opt.fixed_stiffness_nm_per_rad.assign(6, std::nullopt);
  opt.fixed_stiffness_nm_per_rad[0] = k_true[0];
  opt.fixed_stiffness_nm_per_rad[4] = k_true[4];
  const StiffnessEstimate est = identify_stiffness(model, data, opt);
  EXPECT_EQ(est.fixed_joints, (std::vector<int>{1, 5}));
  EXPECT_EQ(est.std_error_nm_per_rad[0], 0.0);
  for (int j = 0; j < 6; ++j) {
    EXPECT_NEAR(est.stiffness_nm_per_rad[static_cast<std::size_t>(j)] / k_true[j], 1.0, 1e-9) << "joint " << j + 1;
  }
  // A wrong fixed value shows up as residual, not silently absorbed into a perfect fit.
  opt.fixed_stiffness_nm_per_rad[0] = 0.5 * k_true[0];
  EXPECT_GT(identify_stiffness(model, data, opt).residual_rms_m, 1e-6);
}

TEST(IdentifyStiffness, AWeightOfTwoCountsLikeTheMeasurementTakenTwice) {
  const RobotModel truth = kr210_model();
  auto data = deflected_data(truth, 40, 20e-6, 21);
  auto doubled = data;
  for (std::size_t i = 0; i < data.size(); i += 3) {
    data[i].weight = 2.0;
    doubled.push_back(doubled[i]);
  }
  IdentificationOptions plain;
  plain.robust = false;
  const StiffnessEstimate a = identify_stiffness(truth, data, plain);
  const StiffnessEstimate b = identify_stiffness(truth, doubled, plain);
  for (std::size_t j = 0; j < 6; ++j) {
    EXPECT_NEAR(a.stiffness_nm_per_rad[j] / b.stiffness_nm_per_rad[j], 1.0, 1e-10) << "joint " << j + 1;
  }
}

TEST(IdentifyStiffness, RegressorBlockIsTheTcpMotionPerUnitComplianceAndDoesNotAllocate) {
  const RobotModel model = kr210_model();
  Workspace ws(model);
  std::mt19937 rng(2);
  const JointVector q = random_configuration(model, rng);
  const Wrench w = random_wrench(rng, true);
  Jacobian block(6, 6);
  {
    test::AllocationGuard guard;
    stiffness_regressor(model, ws, q, w, block);
    EXPECT_EQ(guard.allocations(), 0u);
  }
  // Column j times c_j summed over j: the core's first-order TCP deflection.
  const Displacement dx = tcp_deflection(model, ws, q, w);
  EXPECT_LT((block * model.compliance() - dx).norm(), 1e-12 * dx.norm());
}

TEST(IdentifyStiffness, BadInputIsAnErrorNamingTheMeasurement) {
  const RobotModel model = kr210_model();
  auto data = kdl_linear_data(model, model.stiffness(), 5, true, false, 1);
  data[2].q.resize(5);
  data[2].line = 17;
  try {
    (void)identify_stiffness(model, data);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 17"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)identify_stiffness(model, {}), InputError);
  data = kdl_linear_data(model, model.stiffness(), 5, true, false, 1);
  data[1].dp_m[0] = std::nan("");
  EXPECT_THROW((void)identify_stiffness(model, data), InputError);
  data = kdl_linear_data(model, model.stiffness(), 5, true, false, 1);
  IdentificationOptions opt;
  opt.fixed_stiffness_nm_per_rad.assign(3, std::nullopt);
  EXPECT_THROW((void)identify_stiffness(model, data, opt), InputError);
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

// The compact store is reduced by QR a slab of 512 rows at a time; over 3000 measurements (about
// 18 slabs, mixed 3- and 6-row measurements, uneven weights) the plain fit must equal a dense
// least-squares solve of the whole stacked system, built here from KDL's Jacobian (the compliances
// are positive, so the c >= 0 bound is inactive and NNLS is least squares).
TEST(IdentifyStiffness, TheSlabwiseSolveEqualsADenseSolveOfTheWholeStack) {
  const RobotModel model = kr210_model();
  const JointVector k_true = model.stiffness();
  auto data = kdl_linear_data(model, k_true, 3000, true, false, 99);
  const auto with_rotation = kdl_linear_data(model, k_true, 500, true, true, 98);
  data.insert(data.begin() + 1000, with_rotation.begin(), with_rotation.end());
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 20e-6);
  for (std::size_t i = 0; i < data.size(); ++i) {
    data[i].dp_m += Vector3(noise(rng), noise(rng), noise(rng));
    data[i].weight = 0.5 + static_cast<double>(i % 7) * 0.25;
  }
  IdentificationOptions plain;
  plain.robust = false;
  const StiffnessEstimate est = identify_stiffness(model, data, plain);

  // Dense: rows sqrt(w) [J_lin diag(J^T W)], rhs sqrt(w) dp (and the rotation rows, scale 1 m).
  const KDL::Chain chain = test::kdl_chain_from_dh(model);
  KDL::ChainJntToJacSolver solver(chain);
  Eigen::Index rows = 0;
  for (const auto& m : data) {
    rows += m.drot_rad ? 6 : 3;
  }
  Eigen::MatrixXd A(rows, 6);
  Eigen::VectorXd b(rows);
  Eigen::Index r = 0;
  for (const auto& m : data) {
    KDL::JntArray qk(6);
    for (unsigned j = 0; j < 6; ++j) {
      qk(j) = m.q[j];
    }
    KDL::Jacobian jk(6);
    ASSERT_GE(solver.JntToJac(qk, jk), 0);
    const Eigen::MatrixXd J = jk.data;
    const Eigen::VectorXd tau = J.transpose() * m.wrench_base;
    const double sw = std::sqrt(m.weight);
    const int k = m.drot_rad ? 6 : 3;
    A.middleRows(r, k) = sw * J.topRows(k) * tau.asDiagonal();
    b.segment(r, 3) = sw * m.dp_m;
    if (m.drot_rad) {
      b.segment(r + 3, 3) = sw * *m.drot_rad;
    }
    r += k;
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  for (int j = 0; j < 6; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    EXPECT_NEAR(est.compliance_rad_per_nm[ju], c[j], 1e-9 * c[j]) << "joint " << j + 1;
  }
  // The standard errors from the slabwise R against the dense (A^T A)^-1.
  const Eigen::VectorXd res = b - A * c;
  const double sigma2 = res.squaredNorm() / static_cast<double>(rows - 6);
  const Eigen::MatrixXd cov = sigma2 * (A.transpose() * A).inverse();
  for (int j = 0; j < 6; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    EXPECT_NEAR(est.compliance_std_error_rad_per_nm[ju], std::sqrt(cov(j, j)), 1e-6 * std::sqrt(cov(j, j)))
        << "joint " << j + 1;
  }
  EXPECT_EQ(est.measurements, 3500);
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

// Rows beyond the memory budget go to a scratch file and come back for every pass: the estimate
// must be the in-memory one bit for bit, through fixed joints (rows rewritten in place), 3- and
// 6-row measurements across chunk boundaries, and the robust re-weighting with outliers.
TEST(IdentifyStiffness, RowsKeptInAScratchFileGiveTheSameEstimateBitForBit) {
  const RobotModel truth = kr210_model();
  std::vector<StiffnessMeasurement> data = deflected_data(truth, 60000, 20e-6, 41);
  std::mt19937 rng(43);
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (i % 7 == 0) {
      data[i].drot_rad = Vector3(1e-6, -2e-6, 0.5e-6);
    }
    if (i % 97 == 0) {
      data[i].dp_m += Vector3(0.5e-3, -0.3e-3, 0.2e-3);  // gross outliers for Tukey to reject
    }
    data[i].line = static_cast<int>(i) + 2;
  }
  const auto run = [&](std::size_t budget, std::uint64_t& scratch) {
    IdentificationOptions o;
    o.rows_in_memory_bytes = budget;
    o.fixed_stiffness_nm_per_rad.assign(6, std::nullopt);
    o.fixed_stiffness_nm_per_rad[5] = truth.stiffness()[5];
    StiffnessIdentifier id(truth, o);
    for (const StiffnessMeasurement& m : data) {
      id.add(m);
    }
    scratch = id.scratch_bytes();
    return id.solve();
  };
  std::uint64_t in_memory_scratch = 0, spilled_scratch = 0;
  const StiffnessEstimate a = run(std::size_t{1} << 30, in_memory_scratch);
  const StiffnessEstimate b = run(0, spilled_scratch);
  EXPECT_EQ(in_memory_scratch, 0U);
  // Everything but the chunk still filling (at most 16k rows of 7 doubles) went to the file.
  std::uint64_t row_bytes = 0;
  for (const StiffnessMeasurement& m : data) {
    row_bytes += (m.drot_rad ? 6U : 3U) * 7U * sizeof(double);
  }
  EXPECT_GE(spilled_scratch + 16384U * 7U * sizeof(double), row_bytes);
  EXPECT_LT(spilled_scratch, row_bytes);
  EXPECT_GT(a.iterations, 2);
  EXPECT_FALSE(a.rejected_lines.empty());
  EXPECT_EQ(a.stiffness_nm_per_rad, b.stiffness_nm_per_rad);
  EXPECT_EQ(a.std_error_nm_per_rad, b.std_error_nm_per_rad);
  EXPECT_EQ(a.robust_weights, b.robust_weights);
  EXPECT_EQ(a.rejected_lines, b.rejected_lines);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.sigma_m, b.sigma_m);
  EXPECT_EQ(a.residual_rms_m, b.residual_rms_m);
  EXPECT_EQ(a.condition_number, b.condition_number);
  EXPECT_EQ(a.warnings, b.warnings);
  // And the estimate is right, not just repeatable: joints 1..5 within 5 standard errors of the truth.
  for (int j = 0; j < 5; ++j) {
    EXPECT_NEAR(b.stiffness_nm_per_rad[static_cast<std::size_t>(j)], truth.stiffness()[j],
                5.0 * b.std_error_nm_per_rad[static_cast<std::size_t>(j)])
        << "joint " << j + 1;
  }
}

// With nowhere to write the scratch file the identification stops with an error naming the
// directory and what to do, not a crash or a partial result.
TEST(IdentifyStiffness, AScratchFileThatCannotBeMadeIsAnErrorNamingTheDirectory) {
  const RobotModel truth = kr210_model();
  const std::vector<StiffnessMeasurement> data = deflected_data(truth, 25000, 20e-6, 5);
  const char* old = std::getenv("TMPDIR");
  const std::string saved = old != nullptr ? old : "";
  ::setenv("TMPDIR", "/proc", 1);  // a directory no one can create files in, root included
  IdentificationOptions o;
  o.rows_in_memory_bytes = 0;
  std::string message;
  try {
    StiffnessIdentifier id(truth, o);
    for (const StiffnessMeasurement& m : data) {
      id.add(m);
    }
    (void)id.solve();
  } catch (const Error& e) {
    message = e.what();
  }
  if (old != nullptr) {
    ::setenv("TMPDIR", saved.c_str(), 1);
  } else {
    ::unsetenv("TMPDIR");
  }
  EXPECT_NE(message.find("identification rows"), std::string::npos) << message;
  EXPECT_NE(message.find("/proc"), std::string::npos) << message;
  EXPECT_NE(message.find("TMPDIR"), std::string::npos) << message;
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

// The robust fit ends with a solve at its final weights: it must be the dense weighted least squares of the whole
// stack (KDL's Jacobians, every measurement's rows times sqrt(weight * robust weight)) at those weights, with the
// residual figures of that solve, and it must name the rejected measurements by the lines they came from (lines
// with gaps, as comments in a file leave, and weights that differ from 1 from the start or only from the middle).
void expect_dense_solve_at_final_weights(std::size_t first_weighted) {
  const RobotModel model = kr210_model();
  std::vector<StiffnessMeasurement> data = deflected_data(model, 3000, 20e-6, 77);
  for (std::size_t i = 0; i < data.size(); ++i) {
    data[i].line = static_cast<int>(i + 2 + i / 100);
    data[i].weight = i < first_weighted ? 1.0 : 0.5 + static_cast<double>(i % 5) * 0.25;
    if (i % 50 == 0) {
      data[i].dp_m.x() += 1e-3;  // a gross outlier: 50 noise sigmas
    }
  }
  const StiffnessEstimate est = identify_stiffness(model, data);
  ASSERT_EQ(est.robust_weights.size(), data.size());
  ASSERT_GT(est.iterations, 2);

  const KDL::Chain chain = test::kdl_chain_from_dh(model);
  KDL::ChainJntToJacSolver solver(chain);
  Eigen::MatrixXd A(3 * static_cast<Eigen::Index>(data.size()), 6);
  Eigen::VectorXd b(A.rows());
  for (std::size_t i = 0; i < data.size(); ++i) {
    const StiffnessMeasurement& m = data[i];
    KDL::JntArray qk(6);
    for (unsigned j = 0; j < 6; ++j) {
      qk(j) = m.q[j];
    }
    KDL::Jacobian jk(6);
    ASSERT_GE(solver.JntToJac(qk, jk), 0);
    const Eigen::MatrixXd J = jk.data;
    const Eigen::VectorXd tau = J.transpose() * m.wrench_base;
    const double sw = std::sqrt(m.weight * est.robust_weights[i]);
    const auto r = 3 * static_cast<Eigen::Index>(i);
    A.middleRows(r, 3) = sw * J.topRows(3) * tau.asDiagonal();
    b.segment(r, 3) = sw * m.dp_m;
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  for (std::size_t j = 0; j < 6; ++j) {
    EXPECT_NEAR(est.compliance_rad_per_nm[j], c[static_cast<Eigen::Index>(j)], 1e-9 * c[static_cast<Eigen::Index>(j)])
        << "joint " << j + 1;
  }
  // The residual RMS of the measurements kept, in the measured unit (each row divided by sqrt(weight)).
  double pos2 = 0.0;
  int kept = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (est.robust_weights[i] > 0.0) {
      const StiffnessMeasurement& m = data[i];
      KDL::JntArray qk(6);
      for (unsigned j = 0; j < 6; ++j) {
        qk(j) = m.q[j];
      }
      KDL::Jacobian jk(6);
      ASSERT_GE(solver.JntToJac(qk, jk), 0);
      const Eigen::MatrixXd J = jk.data;
      const Eigen::VectorXd tau = J.transpose() * m.wrench_base;
      pos2 += (m.dp_m - J.topRows(3) * tau.asDiagonal() * c).squaredNorm();
      ++kept;
    }
  }
  EXPECT_NEAR(est.residual_rms_m, std::sqrt(pos2 / (3.0 * kept)), 1e-9 * est.residual_rms_m);

  // Every outlier rejected, named by its own line.
  ASSERT_EQ(est.rejected_lines.size(), est.rejected_measurements.size());
  for (std::size_t k = 0; k < est.rejected_measurements.size(); ++k) {
    const auto i = static_cast<std::size_t>(est.rejected_measurements[k]);
    EXPECT_EQ(est.rejected_lines[k], data[i].line);
  }
  for (std::size_t i = 0; i < data.size(); i += 50) {
    EXPECT_EQ(est.robust_weights[i], 0.0) << "outlier " << i;
  }
}

TEST(IdentifyStiffness, TheRobustFitIsTheDenseSolveAtItsFinalWeights) {
  expect_dense_solve_at_final_weights(0);     // weights other than 1 from the first measurement
  expect_dense_solve_at_final_weights(1500);  // only from the middle on
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

// The re-weighting solves its steps from the weighted sums of the rows' products (the normal equations), summed a
// measurement at a time and two sums at a time; only its last solve is a QR of the rows. Every step must be the
// dense weighted least squares of the whole stack at that step's weights (KDL's Jacobians; 3- and 6-row
// measurements, uneven weights, rows in the scratch file): the robust weights it ends with come from the residuals
// of those steps, so they must be the weights the dense steps give. Two Huber and two Tukey iterations, with
// outliers that Huber only down-weights and outliers that Tukey rejects.
TEST(IdentifyStiffness, EveryReweightingStepIsTheDenseSolveAtItsWeights) {
  const RobotModel model = kr210_model();
  const JointVector k_true = model.stiffness();
  std::vector<StiffnessMeasurement> data = kdl_linear_data(model, k_true, 2500, true, false, 61);
  const auto with_rotation = kdl_linear_data(model, k_true, 500, true, true, 62);
  data.insert(data.begin() + 1200, with_rotation.begin(), with_rotation.end());
  std::mt19937 rng(63);
  std::normal_distribution<double> noise(0.0, 20e-6);
  for (std::size_t i = 0; i < data.size(); ++i) {
    StiffnessMeasurement& m = data[i];
    m.dp_m += Vector3(noise(rng), noise(rng), noise(rng));
    if (m.drot_rad) {
      *m.drot_rad += Vector3(noise(rng), noise(rng), noise(rng));  // rad, weighed like m (rotation_scale_m 1)
    }
    m.weight = 0.5 + static_cast<double>(i % 4) * 0.5;
    if (i % 40 == 0) {
      m.dp_m.x() += 1e-3;  // 50 sigmas: Tukey rejects it
    } else if (i % 40 == 20) {
      m.dp_m.y() += 80e-6;  // 4 sigmas: Huber down-weights it
    }
  }
  IdentificationOptions options;
  options.max_robust_iterations = 2;
  options.rows_in_memory_bytes = 0;
  const StiffnessEstimate est = identify_stiffness(model, data, options);
  ASSERT_EQ(est.iterations, 4);  // neither stage converged in two: every step below ran
  ASSERT_EQ(est.robust_weights.size(), data.size());

  // The dense stack: sqrt(weight) [J diag(J^T W)] and sqrt(weight) [dp; drot], each measurement's rows in turn.
  const KDL::Chain chain = test::kdl_chain_from_dh(model);
  KDL::ChainJntToJacSolver solver(chain);
  std::vector<Eigen::Index> first, count;
  Eigen::Index rows = 0;
  for (const auto& m : data) {
    first.push_back(rows);
    count.push_back(m.drot_rad ? 6 : 3);
    rows += count.back();
  }
  Eigen::MatrixXd A(rows, 6);
  Eigen::VectorXd b(rows);
  for (std::size_t i = 0; i < data.size(); ++i) {
    const StiffnessMeasurement& m = data[i];
    KDL::JntArray qk(6);
    for (unsigned j = 0; j < 6; ++j) {
      qk(j) = m.q[j];
    }
    KDL::Jacobian jk(6);
    ASSERT_GE(solver.JntToJac(qk, jk), 0);
    const Eigen::MatrixXd J = jk.data;
    const Eigen::VectorXd tau = J.transpose() * m.wrench_base;
    const double sw = std::sqrt(m.weight);
    A.middleRows(first[i], count[i]) = sw * J.topRows(count[i]) * tau.asDiagonal();
    b.segment(first[i], 3) = sw * m.dp_m;
    if (m.drot_rad) {
      b.segment(first[i] + 3, 3) = sw * *m.drot_rad;
    }
  }
  const auto solve = [&](const std::vector<double>& w) {
    Eigen::MatrixXd Aw = A;
    Eigen::VectorXd bw = b;
    for (std::size_t i = 0; i < data.size(); ++i) {
      Aw.middleRows(first[i], count[i]) *= std::sqrt(w[i]);
      bw.segment(first[i], count[i]) *= std::sqrt(w[i]);
    }
    return Eigen::VectorXd(Aw.colPivHouseholderQr().solve(bw));
  };
  const auto residuals = [&](const Eigen::VectorXd& c) {
    std::vector<double> d(data.size());
    for (std::size_t i = 0; i < data.size(); ++i) {
      d[i] = (b.segment(first[i], count[i]) - A.middleRows(first[i], count[i]) * c).norm();
    }
    return d;
  };
  // The estimator's thresholds (docs/identify.md): Wilson-Hilferty chi quantiles for k = 3 or 6 rows.
  const auto chi = [](Eigen::Index k, double z) {
    const double a = 2.0 / (9.0 * static_cast<double>(k));
    const double t = 1.0 - a + z * std::sqrt(a);
    return std::sqrt(static_cast<double>(k) * t * t * t);
  };
  const auto huber = [&](const std::vector<double>& d, double sigma) {
    std::vector<double> w(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) {
      const double u = d[i] / sigma, h = chi(count[i], 1.645);
      w[i] = u <= h ? 1.0 : h / u;
    }
    return w;
  };
  const auto tukey = [&](const std::vector<double>& d, double sigma) {
    std::vector<double> w(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) {
      const double t = d[i] / sigma / (1.42 * chi(count[i], 3.090));
      w[i] = t < 1.0 ? (1.0 - t * t) * (1.0 - t * t) : 0.0;
    }
    return w;
  };
  const auto scale = [&](const std::vector<double>& d) {  // median of d_i / chi median, an even count
    std::vector<double> u(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) {
      u[i] = d[i] / chi(count[i], 0.0);
    }
    std::sort(u.begin(), u.end());
    return 0.5 * (u[u.size() / 2 - 1] + u[u.size() / 2]);
  };
  std::vector<double> d = residuals(solve(std::vector<double>(data.size(), 1.0)));
  double sigma = 0.0;
  for (int it = 0; it < 2; ++it) {  // Huber, the scale from each step's residuals
    sigma = scale(d);
    d = residuals(solve(huber(d, sigma)));
  }
  std::vector<double> omega = tukey(d, sigma);  // Tukey, the scale frozen
  omega = tukey(residuals(solve(omega)), sigma);

  int down = 0, rejected = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    EXPECT_NEAR(est.robust_weights[i], omega[i], 1e-9) << "measurement " << i;
    down += static_cast<int>(omega[i] > 0.0 && omega[i] < 0.5);
    rejected += static_cast<int>(omega[i] == 0.0);
  }
  EXPECT_GE(rejected, 75);  // the 50-sigma outliers, at least
  EXPECT_GT(down, 0);
  const Eigen::VectorXd c = solve(omega);
  for (std::size_t j = 0; j < 6; ++j) {
    EXPECT_NEAR(est.compliance_rad_per_nm[j], c[static_cast<Eigen::Index>(j)], 1e-9 * c[static_cast<Eigen::Index>(j)])
        << "joint " << j + 1;
  }
}

}  // namespace
}  // namespace deflex
