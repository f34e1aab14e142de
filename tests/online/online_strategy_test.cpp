// The online strategies against the wrench they must hand the compensator, worked out here from the
// LDBB's geometry (force along the bar from the pivot): hybrid corrects only measured minus modelled
// force at the pose the controller reports; predictive adds the model's change from that pose to the
// one the command is for, or leads along the measured slope without a model; none holds. The
// compensator then applies the offset and the lead to its conditioned wrench.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/force/wrench_table_model.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "online/fd_jacobian.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

RobotModel tool_robot() {
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0.0, 0.0, 0.3);
  return builtin_irb6700().with_tool(tool);
}

JointVector pose_deg(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << a, b, c, d, e, f;
  return q * (kPi / 180.0);
}

Vector3 tcp_of(const RobotModel& m, const JointVector& q) {
  Workspace ws(m);
  return tcp_pose(m, ws, q).translation();
}

TEST(OnlineStrategy, HybridSubtractsTheModelForceAtTheFeedbackPose) {
  const RobotModel robot = tool_robot();
  FrameCache frames(robot);
  const Vector3 pivot(1.6, 0.1, 0.6);
  const LdbbForceModel ldbb(pivot, 400.0, true);
  OnlineStrategy s(robot, StrategyKind::kHybrid, &ldbb);
  const JointVector fb = pose_deg(3, 28, 8, 5, 52, -4), target = pose_deg(5, 27, 9, 5, 51, -3);
  CycleInput in;
  ASSERT_EQ(s.prepare(in, fb, target, 0.05, 0.009, frames), StrategyStatus::kOk);
  const Vector3 bar = tcp_of(robot, fb) - pivot;
  EXPECT_LT((in.wrench_offset_base.head<3>() + 400.0 * bar.normalized()).norm(), 1e-9);
  EXPECT_LT(in.wrench_offset_base.tail<3>().norm(), 1e-9);  // WAP = TCP: no moment
  EXPECT_EQ(in.wrench_lead_s, 0.0);
  EXPECT_FALSE(in.hold_to_zero);
}

TEST(OnlineStrategy, PredictiveAddsTheModelsChangeOrLeadsAlongTheSlope) {
  const RobotModel robot = tool_robot();
  FrameCache frames(robot);
  const Vector3 pivot(1.6, 0.1, 0.6);
  const LdbbForceModel ldbb(pivot, 650.0, false);
  const JointVector fb = pose_deg(3, 28, 8, 5, 52, -4), target = pose_deg(6, 27, 9, 5, 51, -3);
  CycleInput in;
  OnlineStrategy with_model(robot, StrategyKind::kPredictive, &ldbb);
  ASSERT_EQ(with_model.prepare(in, fb, target, 0.06, 0.009, frames), StrategyStatus::kOk);
  const Vector3 at_fb = -650.0 * (tcp_of(robot, fb) - pivot).normalized();
  const Vector3 at_target = -650.0 * (tcp_of(robot, target) - pivot).normalized();
  EXPECT_LT((in.wrench_offset_base.head<3>() - (at_target - at_fb)).norm(), 1e-9);
  EXPECT_DOUBLE_EQ(in.wrench_lead_s, 0.009);  // only the filter's lag along the slope
  OnlineStrategy without(robot, StrategyKind::kPredictive, nullptr);
  ASSERT_EQ(without.prepare(in, fb, target, 0.06, 0.009, frames), StrategyStatus::kOk);
  EXPECT_TRUE(in.wrench_offset_base.isZero());
  EXPECT_DOUBLE_EQ(in.wrench_lead_s, 0.069);  // the link delay and the filter's lag
}

TEST(OnlineStrategy, NoneHoldsAndBadConfigurationsAreRefused) {
  const RobotModel robot = tool_robot();
  FrameCache frames(robot);
  OnlineStrategy none(robot, StrategyKind::kNone, nullptr);
  CycleInput in;
  ASSERT_EQ(none.prepare(in, pose_deg(0, 20, 10, 0, 60, 0), pose_deg(0, 20, 10, 0, 60, 0), 0.05, 0.009, frames),
            StrategyStatus::kOk);
  EXPECT_TRUE(in.hold_to_zero);
  EXPECT_THROW(OnlineStrategy(robot, StrategyKind::kHybrid, nullptr), InputError);
  const WrenchTableModel table(CsvTable::parse("index,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm\n0,1,0,0,0,0,0\n", "t.csv"));
  EXPECT_THROW(OnlineStrategy(robot, StrategyKind::kHybrid, &table), InputError);
  EXPECT_THROW((void)parse_strategy("telepathy"), InputError);
  EXPECT_EQ(parse_strategy("predictive"), StrategyKind::kPredictive);
  // At the LDBB's pivot the model has no direction: the cycle is held, never divided through.
  const Vector3 tcp = tcp_of(robot, pose_deg(0, 20, 10, 0, 60, 0));
  const LdbbForceModel at_pivot(tcp, 100.0, true);
  OnlineStrategy hybrid(robot, StrategyKind::kHybrid, &at_pivot);
  EXPECT_EQ(hybrid.prepare(in, pose_deg(0, 20, 10, 0, 60, 0), pose_deg(0, 20, 10, 0, 60, 0), 0.05, 0.009, frames),
            StrategyStatus::kModelForceUnavailable);
}

TEST(OnlineStrategy, PrepareDoesNotAllocate) {
  const RobotModel robot = tool_robot();
  FrameCache frames(robot);
  const LdbbForceModel ldbb(Vector3(1.6, 0.1, 0.6), 400.0, true);
  OnlineStrategy s(robot, StrategyKind::kPredictive, &ldbb);
  CycleInput in;
  const JointVector fb = pose_deg(3, 28, 8, 5, 52, -4), target = pose_deg(5, 27, 9, 5, 51, -3);
  (void)s.prepare(in, fb, target, 0.05, 0.009, frames);
  test::AllocationGuard guard;
  for (int i = 0; i < 100; ++i) (void)s.prepare(in, fb, target, 0.05, 0.009, frames);
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
