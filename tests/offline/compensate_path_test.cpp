// Offline compensation: the model-consistent round trip (the deflected arm at the compensated joints
// is on the desired path), the exact form computed here from J and K, the predicted deflection
// against the first-order C W, the moment moved to the WAP, and the input errors.
#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/force/wrench_table_model.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

const Eigen::Quaterniond kDown(0.0, 0.0, 1.0, 0.0);

struct PaperCase {
  RobotModel model = builtin_irb6700();
  CirclePath circle = default_circle();
  std::vector<Pose> poses = sample_circle(circle, kDown);
  JointPath path = solve_path_ik(model, poses, IkRequest{});
  // The LDBB 100 mm below the centre: bar inclined 45 deg, 141 mm long.
  Vector3 pivot = Vector3(1.5, 0.0, 0.9);
};

TEST(CompensatePath, DeflectedArmAtTheCompensatedJointsIsOnTheDesiredPath) {
  const PaperCase pc;
  for (double load : {125.0, 375.0, 625.0}) {
    const LdbbForceModel force(pc.pivot, load, true);
    const OfflineResult r = compensate_path(pc.model, pc.path, pc.poses, force);
    ASSERT_EQ(r.points.size(), 81u);
    Workspace ws(pc.model);
    JointVector q_actual;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      const OfflinePoint& p = r.points[i];
      // The wrench the model will see is the LDBB force (moment zero: the WAP is the TCP).
      EXPECT_NEAR((p.wrench_base - force.wrench_at(i, pc.poses[i])).norm(), 0.0, 1e-12);
      ASSERT_EQ(deflected_configuration(pc.model, ws, p.q_command, p.wrench_base, q_actual),
                DeflectionStatus::kConverged);
      const Pose reached = tcp_pose(pc.model, ws, q_actual);
      EXPECT_LT((reached.translation() - pc.poses[i].translation()).norm(), 1e-9) << load << " N, point " << i;
      EXPECT_LT(pose_difference(pc.poses[i], reached).tail<3>().norm(), 1e-9);
      // Without compensation the same load moves the TCP by a visible amount.
      ASSERT_EQ(deflected_configuration(pc.model, ws, p.q_desired, p.wrench_base, q_actual),
                DeflectionStatus::kConverged);
      EXPECT_GT((tcp_pose(pc.model, ws, q_actual).translation() - pc.poses[i].translation()).norm(), 1e-5);
    }
    EXPECT_LT(r.max_residual_m, 1e-9);
  }
}

TEST(CompensatePath, CommandIsTheExactFormFromJacobianAndStiffness) {
  const PaperCase pc;
  const LdbbForceModel force(pc.pivot, 625.0, true);
  const OfflineResult r = compensate_path(pc.model, pc.path, pc.poses, force);
  Workspace ws(pc.model);
  Jacobian J;
  const JointVector k = pc.model.stiffness();
  for (std::size_t i = 0; i < r.points.size(); i += 10) {
    const OfflinePoint& p = r.points[i];
    jacobian(pc.model, ws, p.q_desired, EndPoint::kWap, J);
    const JointVector tau = J.transpose() * p.wrench_base;
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(p.q_command[j], p.q_desired[j] - tau[j] / k[j], 1e-15) << i << " joint " << j;
    }
    // The Cartesian command is FK of the joint command.
    EXPECT_TRUE(p.tcp_command.isApprox(tcp_pose(pc.model, ws, p.q_command), 1e-15));
    EXPECT_EQ(p.configuration_command.cfx, pc.path.configuration.cfx);
  }
}

TEST(CompensatePath, PredictedDeflectionAgreesWithFirstOrderComplianceAndScalesWithLoad) {
  const PaperCase pc;
  const OfflineResult small = compensate_path(pc.model, pc.path, pc.poses, LdbbForceModel(pc.pivot, 125.0, true));
  const OfflineResult large = compensate_path(pc.model, pc.path, pc.poses, LdbbForceModel(pc.pivot, 625.0, true));
  Workspace ws(pc.model);
  Jacobian J;
  const JointVector c = pc.model.compliance();
  double sum = 0.0, max = 0.0;
  for (std::size_t i = 0; i < large.points.size(); ++i) {
    const OfflinePoint& p = large.points[i];
    jacobian(pc.model, ws, p.q_desired, EndPoint::kTcp, J);
    // First order: dx = J K^-1 J^T W. The exact (fixed-point) deflection differs by the change of
    // J over the deflection, ~1e-3 relative at these loads.
    const Displacement first_order = J * (c.asDiagonal() * (J.transpose() * p.wrench_base));
    EXPECT_NEAR((p.predicted_deflection - first_order).norm(), 0.0, 1e-2 * first_order.norm()) << i;
    // Deflection is linear in the load to first order: 625 N gives five times 125 N.
    EXPECT_NEAR(p.predicted_deflection.head<3>().norm(), 5.0 * small.points[i].predicted_deflection.head<3>().norm(),
                1e-2 * p.predicted_deflection.head<3>().norm());
    // A push deflects the TCP away from the pivot: positive along the bar.
    EXPECT_GT(p.predicted_deflection.head<3>().dot(p.wrench_base.head<3>()), 0.0);
    sum += p.predicted_deflection.head<3>().norm();
    max = std::max(max, p.predicted_deflection.head<3>().norm());
  }
  EXPECT_NEAR(large.mean_deflection_m, sum / 81.0, 1e-15);
  EXPECT_DOUBLE_EQ(large.max_deflection_m, max);
  // Same order as the paper's 0.62 mm at 625 N (the built-in stiffness is a literature estimate).
  EXPECT_GT(large.mean_deflection_m, 0.1e-3);
  EXPECT_LT(large.mean_deflection_m, 3e-3);
}

TEST(CompensatePath, MomentIsMovedFromTheTcpToTheWap) {
  // A 200 mm tool with the wrench application point half way: a force at the TCP has a moment
  // (p_tcp - p_wap) x F about the WAP.
  Pose flange_T_tcp = Pose::Identity();
  flange_T_tcp.translation() = Vector3(0, 0, 0.2);
  Pose flange_T_wap = Pose::Identity();
  flange_T_wap.translation() = Vector3(0, 0, 0.1);
  const RobotModel model = builtin_irb6700().with_tool(flange_T_tcp, flange_T_wap);
  const auto poses = sample_circle(default_circle(), kDown);
  const JointPath path = solve_path_ik(model, poses, IkRequest{});
  Wrench w = Wrench::Zero();
  w << 100.0, -50.0, 200.0, 0.0, 0.0, 0.0;
  const OfflineResult r = compensate_path(model, path, poses, ConstantWrenchModel(w));
  Workspace ws(model);
  JointVector q_actual;
  for (std::size_t i = 0; i < r.points.size(); i += 20) {
    forward_kinematics(model, ws, path.q[i]);
    const Vector3 lever = ws.base_T_tcp.translation() - ws.base_T_wap.translation();
    EXPECT_NEAR(lever.norm(), 0.1, 1e-12);
    EXPECT_NEAR((r.points[i].wrench_base.tail<3>() - lever.cross(w.head<3>())).norm(), 0.0, 1e-12);
    ASSERT_EQ(deflected_configuration(model, ws, r.points[i].q_command, r.points[i].wrench_base, q_actual),
              DeflectionStatus::kConverged);
    EXPECT_LT((tcp_pose(model, ws, q_actual).translation() - poses[i].translation()).norm(), 1e-9);
  }
}

TEST(CompensatePath, InputErrors) {
  const PaperCase pc;
  const LdbbForceModel force(pc.pivot, 625.0, true);
  std::vector<Pose> fewer(pc.poses.begin(), pc.poses.end() - 1);
  EXPECT_THROW((void)compensate_path(pc.model, pc.path, fewer, force), InputError);
  const WrenchTableModel table(CsvTable::parse("fx_N,fy_N,fz_N\n1,2,3\n4,5,6\n", "two.csv"));
  try {
    (void)compensate_path(pc.model, pc.path, pc.poses, table);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has 2 points, the path 81"), std::string::npos) << e.what();
  }
  RobotDescription no_k = pc.model.description();
  no_k.stiffness_nm_per_rad.clear();
  EXPECT_THROW((void)compensate_path(RobotModel(no_k), pc.path, pc.poses, force), InputError);
  EXPECT_THROW((void)compensate_path(pc.model, JointPath{}, {}, force), InputError);
  // A load far beyond the model (the pivot force of 5 MN) pushes the arm out of its joint limits
  // or stops the fixed point: an error naming the point, never a command.
  try {
    (void)compensate_path(pc.model, pc.path, pc.poses, LdbbForceModel(pc.pivot, 5e6, true));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("path point 0"), std::string::npos) << e.what();
  }
}

TEST(CompensatePath, WithoutPredictionOnlyTheCommandIsComputed) {
  const PaperCase pc;
  const LdbbForceModel force(pc.pivot, 375.0, true);
  OfflineOptions fast;
  fast.predict = false;
  const OfflineResult a = compensate_path(pc.model, pc.path, pc.poses, force, fast);
  const OfflineResult b = compensate_path(pc.model, pc.path, pc.poses, force);
  EXPECT_FALSE(a.predicted);
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].q_command, b.points[i].q_command);
    EXPECT_EQ(a.points[i].predicted_deflection, Displacement::Zero());
  }
  EXPECT_DOUBLE_EQ(a.max_correction_m, b.max_correction_m);
}

}  // namespace
}  // namespace deflex
