// Broken preconditions of the online pieces refused in every build type (the tests run in Release in
// CI): a strategy handed joint vectors of the wrong count or not finite, on the real-time path (a
// status, no exception, no allocation), and a delay estimator set up with a delay or a window that
// is not a number. Before, the hybrid and model-predictive strategies ran forward kinematics on the
// wrong count, whose InputError left a noexcept function: std::terminate. A NaN initial delay was the
// predictive strategy's lead until the first measurement (every cycle then invalid), and a NaN or
// negative window made the estimator never measure anything.
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

JointVector joints_deg(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << a, b, c, d, e, f;
  return q * (kPi / 180.0);
}

TEST(OnlinePreconditions, AStrategyRefusesJointVectorsOfTheWrongCountOrNotFiniteWithAStatus) {
  const RobotModel robot = builtin_irb6700();
  FrameCache frames(robot);
  const LdbbForceModel ldbb(Vector3(1.6, 0.1, 0.6), 400.0, true);
  Wrench down = Wrench::Zero();
  down[2] = -300.0;
  const ConstantWrenchModel constant(down);
  const JointVector good = joints_deg(3, 28, 8, 5, 52, -4);
  const JointVector five = good.head(5);
  JointVector not_finite = good;
  not_finite[2] = kNaN;
  for (const StrategyKind kind : {StrategyKind::kHybrid, StrategyKind::kPredictive}) {
    for (const ForceModel* force : {static_cast<const ForceModel*>(&ldbb), static_cast<const ForceModel*>(&constant)}) {
      OnlineStrategy s(robot, kind, force);
      CycleInput in;
      StrategyStatus feedback_short, target_short, feedback_nan, target_nan;
      {
        test::AllocationGuard guard;
        feedback_short = s.prepare(in, five, good, 0.05, 0.009, frames);
        target_short = s.prepare(in, good, five, 0.05, 0.009, frames);
        feedback_nan = s.prepare(in, not_finite, good, 0.05, 0.009, frames);
        target_nan = s.prepare(in, good, not_finite, 0.05, 0.009, frames);
        EXPECT_EQ(guard.allocations(), 0u);
      }
      EXPECT_EQ(feedback_short, StrategyStatus::kInvalidInput) << to_string(kind);
      EXPECT_EQ(feedback_nan, StrategyStatus::kInvalidInput) << to_string(kind);
      if (kind == StrategyKind::kPredictive) {  // hybrid never looks at the target
        EXPECT_EQ(target_short, StrategyStatus::kInvalidInput);
        EXPECT_EQ(target_nan, StrategyStatus::kInvalidInput);
      }
      EXPECT_TRUE(in.wrench_offset_base.allFinite());
      EXPECT_EQ(s.prepare(in, good, good, 0.05, 0.009, frames), StrategyStatus::kOk) << to_string(kind);
    }
  }
}

TEST(OnlinePreconditions, ADelayEstimatorWithADelayOrWindowThatIsNotANumberIsRefusedAtSetUp) {
  for (const double delay : {kNaN, -0.01, std::numeric_limits<double>::infinity()}) {
    const std::string error = test::error_of([&] { DelayEstimator e(delay); });
    EXPECT_NE(error.find("initial_delay_s"), std::string::npos) << delay << ": " << error;
  }
  for (const double window : {kNaN, 0.0, -0.5, std::numeric_limits<double>::infinity()}) {
    const std::string error = test::error_of([&] { DelayEstimator e(0.05, window); });
    EXPECT_NE(error.find("window_s"), std::string::npos) << window << ": " << error;
  }
  EXPECT_NO_THROW(DelayEstimator(0.0, 0.5));
}

}  // namespace
}  // namespace deflex
