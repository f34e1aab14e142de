// The objects that keep a reference to a model or a force model refuse a temporary at compile time
// (a deleted rvalue constructor), so `PathCompensator(builtin_irb6700(), ConstantWrenchModel(w))`
// cannot dangle; the objects that need to outlive their arguments copy or share them.
#include <memory>
#include <type_traits>

#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/paths/path_ik.hpp"

namespace deflex {
namespace {

// A temporary model or force model: no constructor takes it.
static_assert(!std::is_constructible_v<PathCompensator, RobotModel, const ConstantWrenchModel&>);
static_assert(!std::is_constructible_v<PathCompensator, const RobotModel&, ConstantWrenchModel>);
static_assert(!std::is_constructible_v<PathCompensator, RobotModel, ConstantWrenchModel>);
static_assert(!std::is_constructible_v<PathIkSolver, RobotModel, const IkRequest&>);
// Named objects: the forms the library means.
static_assert(std::is_constructible_v<PathCompensator, const RobotModel&, const ConstantWrenchModel&>);
static_assert(std::is_constructible_v<PathIkSolver, const RobotModel&, const IkRequest&>);
static_assert(std::is_constructible_v<OnlineStrategy, const RobotModel&, StrategyKind, const ForceModel*>);
// The online compensator and the online strategy copy their model, so a temporary is fine there (the
// strategy's force model is a pointer, which a temporary cannot give without an explicit address).
static_assert(std::is_constructible_v<OnlineStrategy, RobotModel, StrategyKind, const ForceModel*>);
static_assert(std::is_constructible_v<OnlineCompensator, RobotModel, const SensorConfig&, const OnlineConfig&>);

TEST(Ownership, OnlineCompensatorOutlivesTheModelItWasGiven) {
  std::unique_ptr<OnlineCompensator> compensator;
  {
    const RobotModel model = builtin_irb6700();
    compensator = std::make_unique<OnlineCompensator>(model, SensorConfig{}, OnlineConfig{});
  }  // the model is gone; the compensator holds its own copy
  JointVector q(6);
  q << 0.0, 0.5, 0.2, 0.0, 0.9, 0.0;
  EXPECT_EQ(compensator->model().dof(), 6);
  EXPECT_EQ(compensator->model().name(), builtin_irb6700().name());
  CycleInput in;
  in.t_s = 0.0;
  in.q_planned = q;
  in.q_feedback = q;
  const CycleOutput out = compensator->step(in);
  EXPECT_EQ(out.q_command.size(), 6);
}

}  // namespace
}  // namespace deflex
