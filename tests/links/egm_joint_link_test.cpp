// deflex's ABB EGM position-guidance link against a stand-in controller with the real semantics
// (link_harness.hpp): the command never leaves the nominal by more than the bound, converges under a
// constant force (no drift over 100,000 cycles), equals the nominal with zero force, and the failure
// the link exists to avoid (answering "planned minus correction") does walk away on this stand-in.
#include <gtest/gtest.h>

#include "support/poses.hpp"

#include "links/link_harness.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

using test::JointBench;

using test::pose_deg;

TEST(EgmJointLink, ConstantForceConvergesWithinTheBoundAndNeverDriftsOver100000Cycles) {
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  JointBench bench(test::hold_program(test::bench_robot(), q0, 1000.0), q0);
  const Vector3 f_base(150.0, -250.0, -300.0);  // about 430 N
  bench.force.reading = test::reading_at(bench.robot, q0, f_base);
  const JointVector expected = test::model_correction(bench.robot, q0, f_base);
  const double bound = bench.compensator.config().max_joint_correction_rad;
  ASSERT_LT(expected.cwiseAbs().maxCoeff(), bound);  // the bound does not cut this correction

  JointVector at_10k, at_100k;
  double worst = 0.0;
  for (int k = 1; k <= 100000; ++k) {
    // The sensor turns with the arm: its reading is the base-frame force seen at the arm's pose.
    if (k > 1) bench.force.reading = test::reading_at(bench.robot, bench.link.last_cycle().q_feedback, f_base);
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered) << "cycle " << k;
    const LinkCycleRecord& r = bench.link.last_cycle();
    worst = std::max(worst, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff());
    if (k == 10000) at_10k = r.q_command;
  }
  at_100k = bench.link.last_cycle().q_command;
  EXPECT_LE(worst, bound);
  // Converged to nominal minus the model's correction, and still there 90,000 cycles later.
  EXPECT_LT((at_100k - (q0 - expected)).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((at_100k - at_10k).cwiseAbs().maxCoeff(), 1e-12);
  // The controller follows the command: the arm sits at it.
  EXPECT_LT((bench.controller->tick(bench.t_s + 0.004) - at_100k).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(bench.link.counters().guard_trips, 0u);
}

TEST(EgmJointLink, ZeroForceStreamsTheNominalExactly) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(10, -5, 8, 20, -10, 30), 8.0);
  JointBench bench(program, q0);
  bench.force.reading = Vector6::Zero();
  JointVector nominal(6), velocity(6);
  for (int k = 1; k <= 2500; ++k) {
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
    const LinkCycleRecord& r = bench.link.last_cycle();
    // The nominal is the program itself (the arm started exactly at its start: no blend).
    program->sample(r.program_time_s, nominal, &velocity);
    EXPECT_LT((r.q_nominal - nominal).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(r.q_command, r.q_nominal) << "cycle " << k;
  }
}

TEST(EgmJointLink, MovingUnderForceStaysWithinTheBoundAndTheArmFollowsAfterTheMeasuredDelay) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(12, -6, 9, 15, -12, 25), 10.0);
  JointBench bench(program, q0);
  const Vector3 f_base(0.0, 0.0, -650.0);
  double worst = 0.0;
  for (int k = 1; k <= 3000; ++k) {
    // The force follows the tool as the arm moves: a fresh reading at the arm's present pose.
    bench.force.reading = test::reading_at(bench.robot, bench.link.last_cycle().q_feedback, f_base);
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
    const LinkCycleRecord& r = bench.link.last_cycle();
    worst = std::max(worst, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, bench.compensator.config().max_joint_correction_rad);
  EXPECT_GT(worst, 1e-5);  // there was a correction to bound
  // The stand-in follows 48 ms of dead time after a 20 Hz filter and the network (0.4 ms + a tick):
  // the link measures between the dead time and the dead time plus those lags.
  ASSERT_TRUE(bench.link.delay().measured());
  EXPECT_GT(bench.link.delay().delay_s(), 0.048);
  EXPECT_LT(bench.link.delay().delay_s(), 0.048 + 0.008 + 0.0044 + 0.004);
}

TEST(EgmJointLink, AnsweringPlannedMinusCorrectionWalksAwayOnThisStandIn) {
  // What the link must never do, done by hand against the same stand-in: reply with the controller's
  // "planned" (its own last target) minus the correction. The stand-in must show the drift.
  RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryNetwork network(clock);
  MemoryTransport& sensor = network.add_endpoint(test::kSensorAddress, 0.0002);
  MemoryTransport& ctrl = network.add_endpoint(test::kControllerAddress, 0.0002);
  cell::ControllerConfig cc;
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  cell::EgmPositionGuidanceController controller(cc, q0, ctrl, test::kSensorAddress);
  const JointVector dtheta = test::model_correction(robot, q0, Vector3(0, 0, -400));
  EgmCodec codec(6);
  std::vector<unsigned char> buf(2048);
  EgmRobotMessage in;
  EgmSensorMessage out;
  double t = 0.0;
  for (int k = 1; k <= 3000; ++k) {
    t += 0.004;
    clock.set(t);
    controller.tick(t);
    clock.set(t + 0.0002);
    DatagramAddress from;
    const long n = sensor.receive(buf.data(), buf.size(), from);
    ASSERT_GT(n, 0);
    ASSERT_EQ(codec.decode_robot(buf.data(), static_cast<std::size_t>(n), in), EgmDecodeStatus::kOk);
    out.seqno = static_cast<std::uint32_t>(k);
    out.planned_joints_deg = in.planned_joints_deg - dtheta * (180.0 / kPi);
    const std::size_t m = codec.encode_sensor(out, buf.data(), buf.size());
    ASSERT_TRUE(sensor.send_to(buf.data(), m, from));
  }
  // 3000 cycles of subtracting the same correction: the target ran away by thousands of times it.
  EXPECT_GT((controller.target() - q0).cwiseAbs().maxCoeff(), 1000.0 * dtheta.cwiseAbs().maxCoeff());
}

TEST(EgmJointLink, RefusesAStartMoreThanOneDegreeFromTheProgramAndNeverAnswers) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  JointVector arm = q0;
  arm[1] += deg_to_rad(1.5);  // joint 2 is 1.5 deg off
  JointBench bench(test::hold_program(test::bench_robot(), q0, 10.0), arm);
  EXPECT_EQ(bench.tick(), LinkPollResult::kRefused);
  EXPECT_EQ(bench.link.state(), LinkState::kRefused);
  EXPECT_NEAR(bench.link.start_distance()[1], deg_to_rad(1.5), 1e-9);
  EXPECT_LT(bench.link.start_distance()[0], 1e-12);
  for (int k = 0; k < 400; ++k) bench.tick();  // 1.6 s: the controller's 1 s timeout passes
  EXPECT_EQ(bench.link.counters().replies, 0u);
  EXPECT_TRUE(bench.controller->counters().timed_out);
  // The arm never moved.
  EXPECT_EQ(bench.controller->tick(bench.t_s + 0.004), arm);
}

TEST(EgmJointLink, StartsWithinOneDegreeAndBlendsTheOffsetOut) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  JointVector arm = q0;
  arm[2] -= deg_to_rad(0.8);
  EgmJointLinkConfig config;
  config.stream.ramp_in_s = 0.5;
  JointBench bench(test::hold_program(test::bench_robot(), q0, 10.0), arm, StrategyKind::kOnline, nullptr, config);
  bench.force.reading = Vector6::Zero();
  ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);
  EXPECT_LT((bench.link.last_cycle().q_command - arm).cwiseAbs().maxCoeff(),
            1e-12);  // the first command: where the arm is
  for (int k = 0; k < 150; ++k) bench.tick();
  EXPECT_LT((bench.link.last_cycle().q_command - q0).cwiseAbs().maxCoeff(), 1e-12);  // after 0.6 s: the program
}

TEST(EgmJointLink, MessagesFromAnotherSenderAreIgnoredAndCounted) {
  // Two identical benches in lockstep; one also gets a stranger's packets. Their commands must agree.
  const JointVector q0 = pose_deg(5, 25, -5, 20, 35, -15);
  JointBench bench(test::hold_program(test::bench_robot(), q0, 100.0), q0);
  JointBench twin(test::hold_program(test::bench_robot(), q0, 100.0), q0);
  bench.force.reading = twin.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -400));
  MemoryTransport& stranger = bench.network.add_endpoint(test::kStrangerAddress, 0.0);
  for (int k = 0; k < 500; ++k) {
    bench.tick();
    twin.tick();
  }
  // A well-formed EgmRobot from another address, with wild joints and a far sequence number.
  EgmCodec codec(6);
  EgmRobotMessage m;
  m.seqno = 100000;
  m.feedback_joints_deg = m.planned_joints_deg = pose_deg(-30, 40, 20, 90, -40, 100) * (180.0 / kPi);
  m.has_planned = true;
  std::vector<unsigned char> buf(1024);
  const std::size_t n = codec.encode_robot(m, buf.data(), buf.size());
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(stranger.send_to(buf.data(), n, test::kSensorAddress));
    bench.tick();
    twin.tick();
    EXPECT_EQ(bench.link.last_cycle().q_command, twin.link.last_cycle().q_command);
  }
  EXPECT_EQ(bench.link.counters().foreign_sender, 50u);
  DatagramAddress from;
  EXPECT_EQ(stranger.receive(buf.data(), buf.size(), from), -1);  // never answered
}

TEST(EgmJointLink, StaleForceRampsTheCorrectionToZeroWhileTheNominalKeepsStreaming) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(8, 0, 0, 0, 0, 10), 20.0);
  JointBench bench(program, q0);
  bench.force.reading = test::reading_at(bench.robot, q0, Vector3(0, 0, -650));
  for (int k = 0; k < 500; ++k) bench.tick();
  EXPECT_GT(bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-5);
  bench.force.on = false;  // the sensor stops
  double previous = bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff();
  int stale_cycles = 0;
  for (int k = 0; k < 500; ++k) {
    ASSERT_EQ(bench.tick(), LinkPollResult::kAnswered);  // the nominal keeps going out
    const double now = bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff();
    if (bench.link.last_cycle().status == CycleStatus::kStaleForce) {
      ++stale_cycles;
      EXPECT_LE(now, previous);  // never grows once stale
    }
    previous = now;
  }
  // Stale once the 50 ms watchdog ran out (13 cycles of 4 ms), and for the rest.
  EXPECT_GE(stale_cycles, 480);
  EXPECT_EQ(bench.link.last_cycle().dtheta.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(bench.link.last_cycle().status, CycleStatus::kStaleForce);
  EXPECT_EQ(bench.link.last_cycle().q_command, bench.link.last_cycle().q_nominal);
}

TEST(EgmJointLink, ASilenceHoldsTheProgramAndItGoesOnOneCycleLater) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(10, 0, 0, 0, 0, 0), 10.0);
  JointBench bench(program, q0);
  bench.force.reading = Vector6::Zero();
  for (int k = 0; k < 500; ++k) bench.tick();  // 2 s of program
  const double last_sent = bench.link.last_cycle().program_time_s;
  const JointVector last_command = bench.link.last_cycle().q_command;
  bench.t_s += 0.8;  // the controller is silent for 0.8 s (longer than the link's 0.5 s restart silence,
                     // shorter than its own 1 s timeout; its state holds: the stand-in is not ticked)
  bench.controller->tick(bench.t_s);  // it drains nothing and sends its next message
  bench.clock.set(bench.t_s + 0.0002);
  // The controller held deflex's last command, so the link goes on from it: the next target is one
  // cycle of the program further on, not 0.8 s.
  EXPECT_EQ(bench.link.poll(0.0), LinkPollResult::kAnswered);
  const LinkCycleRecord& r = bench.link.last_cycle();
  EXPECT_NEAR(r.program_time_s, last_sent + 0.004, 1e-12);
  JointVector step_allowed(6);
  for (int j = 0; j < 6; ++j) step_allowed[j] = 0.004 * (program->peak_speed()[j] + 1.5 * kPi / 180.0 + 0.2) + 1e-12;
  EXPECT_TRUE(((r.q_command - last_command).cwiseAbs().array() <= step_allowed.array()).all())
      << (r.q_command - last_command).transpose();
  EXPECT_EQ(bench.link.counters().restarts, 1u);
  EXPECT_EQ(bench.link.counters().silences, 1u);
}

TEST(EgmJointLink, SteadyStateCycleDoesNotAllocate) {
  const JointVector q0 = pose_deg(0, 20, 10, 0, 60, 0);
  const auto program = test::sweep_program(test::bench_robot(), q0, pose_deg(8, -3, 4, 10, -5, 12), 5.0);
  const LdbbForceModel ldbb(Vector3(1.5, 0.0, 0.5), 400.0, true);
  for (StrategyKind kind : {StrategyKind::kOnline, StrategyKind::kHybrid, StrategyKind::kPredictive}) {
    JointBench bench(program, q0, kind, &ldbb);
    bench.force.reading = test::reading_at(bench.robot, q0, Vector3(50, 0, -400));
    for (int k = 0; k < 300; ++k) bench.tick();  // warm: every buffer at its size
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
