// One kinematics pass a cycle: on every link and with every strategy, the cycle (the strategy, the
// compensator and the link) runs forward kinematics at most twice a cycle, once at the feedback and
// once at the target, and once where the two are the same configuration. Counted on the cycle's robot
// model object (the compensator's; the stand-in controller's arm is another), tick by tick against
// the stand-in of each controller, with the arm moving and a force on it.
#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/model/frame_cache.hpp"
#include "links/fault_bench.hpp"
#include "support/poses.hpp"

namespace deflex {
namespace {

using runtime::LinkKind;
using test::pose_deg;

struct CycleCase {
  LinkKind link;
  StrategyKind strategy;
  bool with_model;  // predictive: with a force model (the model's wrench at the target too)
  PathCorrFrame frame = PathCorrFrame::kTool;
  JacobianAt jacobian_at = JacobianAt::kPlanned;
};

// The most forward kinematics any cycle of the run took, and the cycles it ran.
struct CycleCount {
  std::uint64_t most = 0, cycles = 0, calls = 0;
};

CycleCount count_kinematics(const CycleCase& c) {
  const RobotModel robot = test::bench_robot();
  const auto program =
      test::sweep_program(robot, pose_deg(0, 20, 10, 0, 60, 0), pose_deg(20, -8, 12, 25, -15, 40), 20.0);
  runtime::SessionConfig config = test::bench_session(c.link);
  config.strategy = c.strategy;
  config.egm_path.frame = c.frame;
  config.online.jacobian_at = c.jacobian_at;
  standin::StandInConfig sc;
  sc.force_base_n = Vector3(0.0, 0.0, -650.0);
  Wrench w = Wrench::Zero();
  w[2] = -600.0;
  const ConstantWrenchModel model(w);
  const bool needs_model = c.strategy == StrategyKind::kHybrid || c.with_model;
  standin::StandInSession s(config, robot, test::bench_sensor(), program, needs_model ? &model : nullptr, sc);
  runtime::Session& session = s.session();
  s.run_for(1.5);  // past the ramp-in, the arm moving
  const KinematicsCallCounter counter(session.compensator().model());
  CycleCount n;
  std::uint64_t calls = 0, cycles = session.compensator().counters().cycles;
  const std::uint64_t first = cycles;
  for (int tick = 0; tick < 500; ++tick) {
    s.tick();
    const std::uint64_t now_cycles = session.compensator().counters().cycles;
    const std::uint64_t now_calls = counter.count();
    if (now_cycles > cycles) {
      n.most = std::max(n.most, (now_calls - calls) / (now_cycles - cycles));
    } else {
      EXPECT_EQ(now_calls, calls) << "kinematics outside a cycle";
    }
    calls = now_calls;
    cycles = now_cycles;
  }
  n.cycles = cycles - first;
  n.calls = calls;
  return n;
}

TEST(KinematicsPerCycle, AtMostOnceAtTheFeedbackAndOnceAtTheTarget) {
  for (LinkKind link : {LinkKind::kEgmJoint, LinkKind::kEgmPath, LinkKind::kRsi, LinkKind::kSimpleMessage,
                        LinkKind::kFanucJ519, LinkKind::kMotoros2Rt, LinkKind::kUrRtde}) {
    for (const auto& [strategy, with_model] : {std::pair{StrategyKind::kOnline, false},
                                               {StrategyKind::kHybrid, true},
                                               {StrategyKind::kPredictive, false},
                                               {StrategyKind::kPredictive, true},
                                               {StrategyKind::kNone, false}}) {
      for (PathCorrFrame frame : {PathCorrFrame::kTool, PathCorrFrame::kPath}) {
        if (frame == PathCorrFrame::kPath && link != LinkKind::kEgmPath) continue;
        const CycleCount n = count_kinematics({link, strategy, with_model, frame});
        SCOPED_TRACE(::testing::Message() << runtime::link_kind(link).name << " " << to_string(strategy)
                                          << (with_model ? " with a model" : "") << " " << to_string(frame));
        ASSERT_GT(n.cycles, 5u);
        EXPECT_LE(n.most, 2u);
        EXPECT_GT(n.calls, 0u);
      }
    }
  }
}

// Where the command is for the configuration the arm is at (egm-path corrects the controller's own
// motion where the arm is, unless a strategy leads it; rsi's is for the controller's setpoint), one
// pass serves the cycle.
TEST(KinematicsPerCycle, OnceWhereTheTargetIsTheFeedback) {
  for (PathCorrFrame frame : {PathCorrFrame::kTool, PathCorrFrame::kFlange, PathCorrFrame::kPath}) {
    SCOPED_TRACE(::testing::Message() << "egm-path " << to_string(frame));
    const CycleCount online = count_kinematics({LinkKind::kEgmPath, StrategyKind::kOnline, false, frame});
    EXPECT_EQ(online.most, 1u);
    const CycleCount hybrid = count_kinematics({LinkKind::kEgmPath, StrategyKind::kHybrid, true, frame});
    EXPECT_EQ(hybrid.most, 1u);
  }
  // The Jacobian at the feedback: one pass on a streaming link too, unless a strategy needs the target.
  const CycleCount joint = count_kinematics(
      {LinkKind::kEgmJoint, StrategyKind::kOnline, false, PathCorrFrame::kTool, JacobianAt::kFeedback});
  EXPECT_EQ(joint.most, 1u);
}

}  // namespace
}  // namespace deflex
