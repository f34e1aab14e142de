// The calibration planner: its poses are reachable and as asked, its loads are what it says, its
// design beats random ones, and running it (simulated) identifies the stiffness as predicted.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deflex/identify/calibration_planner.hpp"
#include "deflex/identify/calibration_simulation.hpp"
#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/model/linear_algebra.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

RobotModel kr210() { return load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r2700.yaml"); }

CalibrationPlanOptions kr210_options() {
  CalibrationPlanOptions o;
  o.region_min_m = Vector3(1.3, -0.4, 0.5);
  o.region_max_m = Vector3(1.9, 0.4, 1.1);
  o.load_n = 800.0;
  o.poses = 10;
  o.loads_per_pose = 2;
  o.grid_per_axis = 3;
  return o;
}

// Smallest singular value of the compliance-scaled regressor, computed here from the core's
// Jacobians and the wrench (not the planner's or the identification's code).
double min_singular_value(const RobotModel& model, const std::vector<std::pair<JointVector, Wrench>>& design) {
  Workspace ws(model);
  const int n = model.dof();
  Eigen::MatrixXd A(3 * static_cast<Eigen::Index>(design.size()), n);
  Jacobian Jw, Jt;
  for (std::size_t i = 0; i < design.size(); ++i) {
    jacobian(model, ws, design[i].first, EndPoint::kWap, Jw);
    jacobian(model, ws, design[i].first, EndPoint::kTcp, Jt);
    for (int j = 0; j < n; ++j) {
      const double tau = Jw.col(j).dot(design[i].second);
      A.block(3 * static_cast<Eigen::Index>(i), j, 3, 1) = Jt.col(j).head<3>() * tau * model.compliance()[j];
    }
  }
  return singular_values(A).minCoeff();
}

TEST(CalibrationPlanner, PosesAreReachableInTheRegionAndLoadsAreWhatTheRowsSay) {
  const RobotModel model = kr210();
  const CalibrationPlanOptions o = kr210_options();
  const CalibrationPlan plan = plan_calibration(model, o);
  ASSERT_EQ(plan.points.size(), 20u);
  EXPECT_GT(plan.reachable_poses, 10);
  Workspace ws(model);
  for (const CalibrationPoint& p : plan.points) {
    EXPECT_TRUE(model.within_limits(p.q));
    const Pose tcp = tcp_pose(model, ws, p.q);
    EXPECT_LT((tcp.translation() - p.base_T_tcp.translation()).norm(), 1e-9);
    EXPECT_TRUE(((tcp.translation() - o.region_min_m).array() > -1e-9).all());
    EXPECT_TRUE(((o.region_max_m - tcp.translation()).array() > -1e-9).all());
    EXPECT_LT((tcp.linear().col(2) - Vector3(0, 0, -1)).norm(), 1e-9) << "tool must point down";
    EXPECT_NEAR(p.wrench_base.head<3>().norm(), o.load_n, 1e-9);
    // The moment about the WAP of the force acting at the load point, within the lever's reach.
    const Vector3 r = p.load_point_base - ws.base_T_wap.translation();
    EXPECT_LT((p.wrench_base.tail<3>() - r.cross(p.wrench_base.head<3>())).norm(), 1e-9);
    EXPECT_TRUE(r.norm() < 1e-12 || std::abs(r.norm() - o.lever_m) < 1e-9);
    // Expected deflection: the core's first-order TCP deflection with the file's stiffness.
    const Displacement dx = tcp_deflection(model, ws, p.q, p.wrench_base);
    EXPECT_LT((p.expected_dp_m - dx.head<3>()).norm(), 1e-12);
  }
  // Poses come with loads_per_pose different loads each.
  for (std::size_t i = 0; i < plan.points.size(); i += 2) {
    EXPECT_EQ(plan.points[i].pose, plan.points[i + 1].pose);
    EXPECT_EQ(plan.points[i].q, plan.points[i + 1].q);
    EXPECT_NE(plan.points[i].wrench_base, plan.points[i + 1].wrench_base);
  }
  std::vector<std::pair<JointVector, Wrench>> design;
  for (const auto& p : plan.points) {
    design.emplace_back(p.q, p.wrench_base);
  }
  EXPECT_NEAR(plan.min_singular_value_m, min_singular_value(model, design), 1e-9 * plan.min_singular_value_m);
  EXPECT_LT(plan.condition_number, 100.0);
  for (double r : plan.predicted_relative_std_error) {
    EXPECT_LT(r, 0.1);
  }
  EXPECT_TRUE(plan.warnings.empty());
}

TEST(CalibrationPlanner, WrittenPlanReadsBackInMillimetresDegreesAndNewtons) {
  const RobotModel model = kr210();
  CalibrationPlanOptions o = kr210_options();
  o.poses = 3;
  const CalibrationPlan plan = plan_calibration(model, o);
  const std::string path = ::testing::TempDir() + "/calibration_plan.csv";
  write_calibration_plan(path, plan, {"made by the planner test"});
  const CsvTable t = CsvTable::read_file(path);
  ASSERT_EQ(t.rows(), plan.points.size());
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const CalibrationPoint& p = plan.points[r];
    EXPECT_EQ(t.at(r, "pose"), static_cast<double>(p.pose));
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(t.at(r, fmt::format("q{}_deg", j + 1)), p.q[j] * 180.0 / kPi, 1e-7);
    }
    const char* const xyz[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(t.at(r, fmt::format("{}_mm", xyz[k])), p.base_T_tcp.translation()[k] * 1000.0, 1e-6);
      EXPECT_NEAR(t.at(r, fmt::format("load_{}_mm", xyz[k])), p.load_point_base[k] * 1000.0, 1e-6);
      EXPECT_NEAR(t.at(r, fmt::format("expected_d{}_mm", xyz[k])), p.expected_dp_m[k] * 1000.0, 1e-9);
    }
    const char* const wrench[6] = {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"};
    for (int k = 0; k < 6; ++k) {
      EXPECT_NEAR(t.at(r, wrench[k]), p.wrench_base[k], 1e-6) << wrench[k];
    }
    // The quaternion is the pose's rotation (either sign).
    const Eigen::Quaterniond q(t.at(r, "qw"), t.at(r, "qx"), t.at(r, "qy"), t.at(r, "qz"));
    EXPECT_TRUE(q.normalized().toRotationMatrix().isApprox(p.base_T_tcp.linear(), 1e-8));
  }
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# made by the planner test\n"), std::string::npos) << text;
}

TEST(CalibrationPlanner, GreedyDesignBeatsRandomDesignsOfTheSameSize) {
  const RobotModel model = kr210();
  const CalibrationPlanOptions o = kr210_options();
  const CalibrationPlan plan = plan_calibration(model, o);
  std::mt19937 rng(5);
  Workspace ws(model);
  std::vector<double> random_sv;
  for (int trial = 0; trial < 15; ++trial) {
    std::vector<std::pair<JointVector, Wrench>> design;
    while (design.size() < plan.points.size()) {
      Pose target = Pose::Identity();
      target.linear() = Eigen::Matrix3d(Eigen::AngleAxisd(kPi, Vector3::UnitY()) *
                                        Eigen::AngleAxisd(kPi / 2 * static_cast<double>(rng() % 4), Vector3::UnitZ()));
      for (int a = 0; a < 3; ++a) {
        target.translation()[a] = std::uniform_real_distribution<double>(o.region_min_m[a], o.region_max_m[a])(rng);
      }
      const IkResult ik = inverse_kinematics(model, ws, target);
      if (!ik.ok()) {
        continue;
      }
      forward_kinematics(model, ws, ik.q);
      Wrench w = Wrench::Zero();
      const int axis = static_cast<int>(rng() % 3);
      w[axis] = (rng() % 2 ? 1.0 : -1.0) * o.load_n;
      const int lever_axis = static_cast<int>(rng() % 3);  // 2: no lever
      if (lever_axis < 2) {
        const Vector3 r = (rng() % 2 ? 1.0 : -1.0) * o.lever_m * ws.base_T_wap.linear().col(lever_axis);
        w.tail<3>() = r.cross(w.head<3>());
      }
      design.emplace_back(ik.q, w);
    }
    random_sv.push_back(min_singular_value(model, design));
  }
  std::sort(random_sv.begin(), random_sv.end());
  EXPECT_GT(plan.min_singular_value_m, random_sv[random_sv.size() / 2]);
  EXPECT_GT(plan.min_singular_value_m, 0.8 * random_sv.back());
}

TEST(CalibrationPlanner, RunningThePlanIdentifiesTheStiffnessAsPredicted) {
  const RobotModel model = kr210();
  CalibrationPlanOptions o = kr210_options();
  o.poses = 15;
  o.noise_m = 10e-6;
  const CalibrationPlan plan = plan_calibration(model, o);
  // The truth differs from the nominal model the plan was made with.
  std::vector<double> k_true = model.description().stiffness_nm_per_rad;
  k_true[1] *= 0.8;
  k_true[4] *= 1.3;
  const RobotModel truth = model.with_stiffness(k_true, "test truth");
  const auto data = simulate_calibration(truth, plan, 10e-6, 3);
  ASSERT_EQ(data.size(), plan.points.size());
  const StiffnessEstimate est = identify_stiffness(model, data);
  EXPECT_TRUE(est.unidentifiable_joints.empty());
  for (std::size_t j = 0; j < 6; ++j) {
    const double k = est.stiffness_nm_per_rad[j], se = est.std_error_nm_per_rad[j];
    EXPECT_LT(std::abs(k - k_true[j]), 4.5 * se) << "joint " << j + 1;
    // The planner predicts se(c)/c_nominal; with the true compliance that is a relative error of
    // predicted * k_true / k_nominal. The noise estimate and the robust weights move it a little.
    const double expected =
        plan.predicted_relative_std_error[j] * k_true[j] / model.stiffness()[static_cast<Eigen::Index>(j)];
    EXPECT_GT(se / k, 0.6 * expected) << "joint " << j + 1;
    EXPECT_LT(se / k, 1.6 * expected) << "joint " << j + 1;
  }
}

TEST(CalibrationPlanner, ForcesOnTheAxisOfJoint6CannotObserveItAndThePlanSaysSo) {
  CalibrationPlanOptions o;
  o.region_min_m = Vector3(1.4, -0.3, 0.8);
  o.region_max_m = Vector3(1.8, 0.3, 1.2);
  o.load_n = 500.0;
  o.poses = 6;
  o.lever_m = 0.0;
  o.grid_per_axis = 2;
  const CalibrationPlan plan = plan_calibration(builtin_irb6700(), o);
  EXPECT_FALSE(std::isfinite(plan.predicted_relative_std_error[5]));
  ASSERT_FALSE(plan.warnings.empty());
  EXPECT_NE(plan.warnings.back().find("joint 6"), std::string::npos) << plan.warnings.back();
  // Why, and what to do, in the plan itself (Python prints only its warnings): the TCP on axis 6.
  EXPECT_FALSE(std::isfinite(plan.condition_number));
  EXPECT_NE(plan.warnings.back().find("lies on axis 6"), std::string::npos) << plan.warnings.back();
  // A lever loads joint 6, but a TCP (reflector) on its axis still never moves when it turns.
  o.lever_m = 0.3;
  EXPECT_FALSE(std::isfinite(plan_calibration(builtin_irb6700(), o).predicted_relative_std_error[5]));
  // With the reflector 80 mm off the axis it becomes observable.
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0.08, 0.0, 0.2);
  const CalibrationPlan with_tool = plan_calibration(builtin_irb6700().with_tool(tool), o);
  EXPECT_LT(with_tool.predicted_relative_std_error[5], 0.1);
  EXPECT_TRUE(std::isfinite(with_tool.condition_number));
}

TEST(CalibrationPlanner, BadRegionsAndOptionsAreInputErrors) {
  const RobotModel model = kr210();
  CalibrationPlanOptions o = kr210_options();
  o.region_min_m = Vector3(8.0, 8.0, 8.0);
  o.region_max_m = Vector3(9.0, 9.0, 9.0);
  EXPECT_THROW((void)plan_calibration(model, o), InputError);
  o = kr210_options();
  o.region_max_m.x() = o.region_min_m.x() - 0.1;
  EXPECT_THROW((void)plan_calibration(model, o), InputError);
  o = kr210_options();
  o.load_n = -5.0;
  EXPECT_THROW((void)plan_calibration(model, o), InputError);
  o = kr210_options();
  o.poses = 0;
  EXPECT_THROW((void)plan_calibration(model, o), InputError);
}

}  // namespace
}  // namespace deflex
