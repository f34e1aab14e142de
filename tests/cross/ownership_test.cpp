// One ownership rule (docs/architecture.md): an object that needs a model, a force model, a clock or a
// trajectory after its constructor returns owns a copy, shares it, or refuses a temporary at compile
// time (a deleted rvalue constructor, checked here with static_assert), so neither
// `StiffnessIdentifier id(builtin_irb6700());` nor a session on a temporary clock compiles; the
// objects that must outlive their arguments' scope (a path compensator returned from the function that
// built its model) copy or share them.
#include <memory>
#include <type_traits>

#include <gtest/gtest.h>

#include "deflex/egm/egm_joint_link.hpp"
#include "deflex/egm/egm_path_link.hpp"
#include "deflex/egm/egm_receiver.hpp"
#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/identify/stiffness_identification.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/paths/line_path.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/sensors/rdt_force_source.hpp"
#include "deflex/simple_message/simple_message_link.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/memory_network.hpp"
#include "deflex/transport/memory_stream.hpp"

namespace deflex {
namespace {

// A temporary of what is kept by reference: no constructor takes it.
static_assert(!std::is_constructible_v<PathCompensator, const RobotModel&, ConstantWrenchModel>);
static_assert(!std::is_constructible_v<PathCompensator, RobotModel, ConstantWrenchModel>);
static_assert(!std::is_constructible_v<PathIkSolver, RobotModel, const IkRequest&>);
static_assert(!std::is_constructible_v<StiffnessIdentifier, RobotModel>);
static_assert(!std::is_constructible_v<StiffnessIdentifier, RobotModel, const IdentificationOptions&>);
// A temporary clock (the links, the session, the in-memory transports, the RDT source keep it).
static_assert(
    !std::is_constructible_v<runtime::Session, const runtime::SessionConfig&, const RobotModel&, const SensorConfig&,
                             std::shared_ptr<const JointTrajectory>, const ForceModel*, ForceSource*, SteadyClock>);
static_assert(
    !std::is_constructible_v<runtime::Session, const runtime::SessionConfig&, const RobotModel&, const SensorConfig&,
                             std::shared_ptr<const JointTrajectory>, const ForceModel*, ForceSource*, ManualClock>);
static_assert(!std::is_constructible_v<MemoryNetwork, SteadyClock>);
static_assert(!std::is_constructible_v<MemoryStreamPair, ManualClock, double>);
static_assert(!std::is_constructible_v<EgmJointLink, OnlineCompensator&, OnlineStrategy&,
                                       std::shared_ptr<const JointTrajectory>, DatagramTransport&, SteadyClock>);
static_assert(
    !std::is_constructible_v<EgmPathLink, OnlineCompensator&, OnlineStrategy&, DatagramTransport&, SteadyClock>);
static_assert(!std::is_constructible_v<RsiLink, OnlineCompensator&, OnlineStrategy&, DatagramTransport&, SteadyClock>);
static_assert(
    !std::is_constructible_v<SimpleMessageLink, OnlineCompensator&, OnlineStrategy&,
                             std::shared_ptr<const JointTrajectory>, StreamTransport&, StreamTransport&, SteadyClock>);
static_assert(!std::is_constructible_v<EgmReceiver, DatagramTransport&, SteadyClock, const RobotModel&,
                                       const EgmReceiverConfig&, LinkCounters&>);
static_assert(!std::is_constructible_v<RdtForceSource, DatagramTransport&, SteadyClock, const DatagramAddress&,
                                       const RdtCalibration&>);
// Named objects: the forms the library means.
static_assert(std::is_constructible_v<PathCompensator, const RobotModel&, const ConstantWrenchModel&>);
static_assert(std::is_constructible_v<PathCompensator, const RobotModel&, std::shared_ptr<const ForceModel>>);
static_assert(std::is_constructible_v<PathIkSolver, const RobotModel&, const IkRequest&>);
static_assert(std::is_constructible_v<StiffnessIdentifier, const RobotModel&>);
static_assert(std::is_constructible_v<runtime::Session, const runtime::SessionConfig&, const RobotModel&,
                                      const SensorConfig&, std::shared_ptr<const JointTrajectory>, const ForceModel*,
                                      ForceSource*, const SteadyClock&>);
static_assert(std::is_constructible_v<MemoryNetwork, const ManualClock&>);
static_assert(std::is_constructible_v<MemoryStreamPair, ManualClock&, double>);
static_assert(
    std::is_constructible_v<RsiLink, OnlineCompensator&, OnlineStrategy&, DatagramTransport&, const SteadyClock&>);
static_assert(
    std::is_constructible_v<EgmPathLink, OnlineCompensator&, OnlineStrategy&, DatagramTransport&, const SteadyClock&>);
static_assert(std::is_constructible_v<EgmJointLink, OnlineCompensator&, OnlineStrategy&,
                                      std::shared_ptr<const JointTrajectory>, DatagramTransport&, const SteadyClock&>);
static_assert(std::is_constructible_v<SimpleMessageLink, OnlineCompensator&, OnlineStrategy&,
                                      std::shared_ptr<const JointTrajectory>, StreamTransport&, StreamTransport&,
                                      const SteadyClock&>);
// No link takes a force source: the session hands it to the cycle (ControllerLink::read_force_from).
static_assert(!std::is_constructible_v<RsiLink, OnlineCompensator&, OnlineStrategy&, DatagramTransport&,
                                       const SteadyClock&, ForceSource*>);
// The path compensator copies its model (a temporary model is fine: nothing refers to it afterwards).
static_assert(std::is_constructible_v<PathCompensator, RobotModel, const ConstantWrenchModel&>);
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

// Built by a function that owned its model and its force model, then used after both are gone: the
// points are those of a compensator whose model is alive (exactly: the same arithmetic).
PathCompensator compensator_of_a_local_model(const Wrench& w) {
  const RobotModel model = builtin_irb6700();
  auto force = std::make_shared<const ConstantWrenchModel>(w);
  return PathCompensator(model, force);
}

TEST(Ownership, APathCompensatorOutlivesTheModelAndTheSharedForceItWasGiven) {
  Wrench w;
  w << 100.0, -200.0, -600.0, 0.0, 20.0, 0.0;
  PathCompensator returned = compensator_of_a_local_model(w);
  const RobotModel model = builtin_irb6700();
  const ConstantWrenchModel force(w);
  PathCompensator alive(model, force);
  LinePath line;
  line.start_m = Vector3(1.6, -0.2, 0.9);
  line.end_m = Vector3(1.6, 0.2, 0.9);
  line.points = 5;
  const std::vector<Pose> poses = sample_line(line, Eigen::Quaterniond(0, 0, 1, 0));
  const JointPath path = solve_path_ik(model, poses, IkRequest{});
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const OfflinePoint a = returned.compensate(i, path.q[i], poses[i]);
    const OfflinePoint& b = alive.compensate(i, path.q[i], poses[i]);
    EXPECT_EQ(a.q_command, b.q_command);
    EXPECT_EQ(a.predicted_residual, b.predicted_residual);
    EXPECT_GT((a.q_command - a.q_desired).cwiseAbs().maxCoeff(), 1e-6);  // a real correction
  }
  EXPECT_EQ(returned.summary().force_description, alive.summary().force_description);
  EXPECT_THROW(PathCompensator(model, std::shared_ptr<const ForceModel>()), InputError);
}

}  // namespace
}  // namespace deflex
