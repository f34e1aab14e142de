// deflex's ABB EGM path-correction link against a stand-in controller with the real semantics
// (link_harness.hpp): each answer carries the whole current offset, so a constant force gives a
// constant offset (no accumulation over 100,000 cycles), zero force gives none, the offset never
// exceeds the TCP bound, and deflex and the controller agree on every correction frame. Answering with
// increments instead walks away on this stand-in.
#include <gtest/gtest.h>

#include "support/poses.hpp"

#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

using test::PathBench;

using test::pose_deg;

TEST(EgmPathLink, ConstantForceGivesAConstantAbsoluteOffsetOver100000Cycles) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  // The controller asks every 4 ms here, so 100,000 answers fit in 400 s of simulated time.
  PathBench bench(test::hold_program(test::bench_robot(), q0, 1000.0), "tool", 0.004);
  const Vector3 f_base(150.0, -250.0, -300.0);
  int answered = 0;
  Vector3 at_10k = Vector3::Zero();
  double largest = 0.0;
  for (int k = 1; answered < 100000; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.controller->tick(bench.t_s), f_base);
    if (bench.tick() == LinkPollResult::kAnswered) ++answered;
    largest = std::max(largest, bench.link.last_cycle().tcp_correction_m.norm());
    if (answered == 10000) at_10k = bench.controller->applied_offset_m();
  }
  const Vector3 at_100k = bench.controller->applied_offset_m();
  // The model's TCP correction at the arm's pose, computed here: -J_p K^-1 J^T W.
  const JointVector q_arm = bench.controller->tick(bench.t_s);
  const JointVector dtheta = test::model_correction(bench.robot, q_arm, f_base);
  const Vector3 expected = -(test::fd_wap_jacobian(bench.robot, q_arm).topRows<3>() * dtheta);
  EXPECT_LT((at_100k - expected).norm(), 1e-8);
  EXPECT_LT((at_100k - at_10k).norm(), 1e-12);
  EXPECT_LE(largest, bench.compensator.config().max_tcp_correction_m);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
}

TEST(EgmPathLink, ZeroForceSendsNoOffset) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  PathBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(10, -5, 8, 20, -10, 30), 8.0));
  bench.force.reading = Vector6::Zero();
  for (int k = 0; k < 2000; ++k) bench.tick();
  EXPECT_GT(bench.link.counters().replies, 150u);
  EXPECT_EQ(bench.controller->applied_offset_m(), Vector3::Zero());
}

TEST(EgmPathLink, DeflexAndTheControllerAgreeOnEveryCorrectionFrame) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const Vector3 f_base(0.0, 120.0, -500.0);
  for (const char* frame : {"tool", "flange", "path"}) {
    // A slow move, so the path frame has a direction and the offset settles between answers.
    PathBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(6, 0, 0, 0, 0, 0), 60.0), frame, 0.024);
    for (int k = 0; k < 5000; ++k) {
      bench.force.reading = test::reading_at(bench.robot, bench.controller->tick(bench.t_s), f_base);
      bench.tick();
    }
    // What deflex meant (its TCP correction, base frame) is what the controller applied, whatever the
    // frame it went through on the wire.
    const Vector3 meant = bench.link.last_cycle().tcp_correction_m;
    EXPECT_GT(meant.norm(), 1e-4) << frame;
    EXPECT_LT((bench.controller->applied_offset_m() - meant).norm(), 0.02 * meant.norm()) << frame;
  }
}

TEST(EgmPathLink, TheToolFrameOffsetIsTheBaseCorrectionSeenFromTheTool) {
  // An independent check of one frame: decode deflex's answer by hand and rotate it with FK.
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  PathBench bench(test::hold_program(test::bench_robot(), q0, 100.0), "tool", 0.048);
  const Vector3 f_base(0.0, 0.0, -600.0);
  for (int k = 0; k < 2000; ++k) {
    bench.force.reading = test::reading_at(bench.robot, bench.controller->tick(bench.t_s), f_base);
    bench.tick();
  }
  Workspace ws(bench.robot);
  forward_kinematics(bench.robot, ws, bench.link.last_cycle().q_feedback);
  const Vector3 base = bench.link.last_cycle().tcp_correction_m;
  // The stand-in's offset came in tool coordinates: R_tool * pos = the base correction.
  EXPECT_LT((bench.controller->applied_offset_m() - base).norm(), 1e-6 * base.norm());
  EXPECT_GT((ws.base_T_tcp.linear().transpose() * base - base).norm(), 1e-5);  // the frame matters here
}

TEST(EgmPathLink, AnsweringWithIncrementsWalksAwayOnThisStandIn) {
  RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryNetwork network(clock);
  MemoryTransport& sensor = network.add_endpoint(test::kSensorAddress, 0.0002);
  MemoryTransport& ctrl = network.add_endpoint(test::kControllerAddress, 0.0002);
  cell::ControllerConfig cc;
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  cell::EgmPathCorrectionController controller(cc, robot, test::hold_program(robot, q0, 100.0), ctrl,
                                               test::kSensorAddress);
  EgmCodec codec(6);
  std::vector<unsigned char> buf(2048);
  EgmRobotMessage in;
  EgmPathCorrMessage out;
  Vector3 accumulated = Vector3::Zero();
  const Vector3 step_mm(0.0, 0.0, 0.2);  // "move 0.2 mm more" every answer
  double t = 0.0;
  for (int k = 1; k <= 2500; ++k) {
    t += 0.004;
    clock.set(t);
    controller.tick(t);
    clock.set(t + 0.0002);
    DatagramAddress from;
    const long n = sensor.receive(buf.data(), buf.size(), from);
    if (n < 0) continue;
    ASSERT_EQ(codec.decode_robot(buf.data(), static_cast<std::size_t>(n), in), EgmDecodeStatus::kOk);
    accumulated += step_mm;
    out.pos_mm = accumulated;
    const std::size_t m = codec.encode_path_corr(out, buf.data(), buf.size());
    ASSERT_TRUE(sensor.send_to(buf.data(), m, from));
  }
  EXPECT_GT(controller.applied_offset_m().norm(), 0.04);  // 200 answers x 0.2 mm: tens of mm
}

TEST(EgmPathLink, SteadyStateCycleDoesNotAllocate) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const LdbbForceModel ldbb(Vector3(1.5, 0.0, 0.5), 400.0, true);
  for (StrategyKind kind : {StrategyKind::kOnline, StrategyKind::kHybrid, StrategyKind::kPredictive}) {
    PathBench bench(test::sweep_program(test::bench_robot(), q0, pose_deg(8, -3, 4, 10, -5, 12), 20.0), "path", 0.004,
                    kind, &ldbb);
    bench.force.reading = test::reading_at(bench.robot, q0, Vector3(50, 0, -400));
    for (int k = 0; k < 300; ++k) bench.tick();
    for (int k = 0; k < 200; ++k) {
      bench.t_s += 0.004;
      bench.clock.set(bench.t_s);
      bench.controller->tick(bench.t_s);
      bench.clock.set(bench.t_s + 0.0002);
      test::AllocationGuard guard;
      const LinkPollResult r = bench.link.poll(0.0);
      EXPECT_EQ(guard.allocations(), 0u) << to_string(kind);
      EXPECT_EQ(r, LinkPollResult::kAnswered);
    }
  }
}

}  // namespace
}  // namespace deflex
